// `crowdslam synth` end to end: a modest real run, stereo layout, and the error paths.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "crowdslam/util/text.h"
#include "test_support.h"

namespace {
namespace fs = std::filesystem;
using crowdslam::test::read_text;
using crowdslam::test::run_cli;
using crowdslam::test::TempDir;

int count_data_lines(const fs::path& path) {
  int n = 0;
  for (const std::string& line : crowdslam::read_lines(path.string())) n += (!line.empty() && line[0] != '#');
  return n;
}

TEST(CliSynth, WritesACompleteRgbdDatasetWithPeople) {
  TempDir tmp;
  const fs::path out = tmp / "seq";
  const auto r = run_cli({"--json", "synth", "--out", out.string(), "--frames", "45", "--people", "3", "--width",
                          "320", "--height", "240", "--trajectory", "handheld", "--seed", "5"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto summary = nlohmann::json::parse(r.out);
  EXPECT_EQ(summary["frames"], 45);
  EXPECT_EQ(count_data_lines(out / "rgb.txt"), 45);
  EXPECT_EQ(count_data_lines(out / "depth.txt"), 45);
  EXPECT_EQ(count_data_lines(out / "groundtruth.txt"), 45);
  EXPECT_EQ(count_data_lines(out / "people_gt.txt"), summary["person_boxes"].get<int>());
  EXPECT_TRUE(fs::is_regular_file(out / "rgb" / "000044.png"));
  EXPECT_TRUE(fs::is_regular_file(out / "depth" / "000044.png"));
  EXPECT_FALSE(fs::exists(out / "rgb" / "000045.png"));
  const std::string settings = read_text(out / "settings.yaml");
  EXPECT_EQ(settings.rfind("%YAML:1.0", 0), 0u);
  EXPECT_NE(settings.find("Camera.fx: 262.5"), std::string::npos);
  EXPECT_NE(settings.find("DepthMapFactor: 5000.0"), std::string::npos);
  const auto meta = nlohmann::json::parse(read_text(out / "synth.json"));
  EXPECT_EQ(meta["seed"], 5);
  EXPECT_EQ(meta["people"], 3);
  EXPECT_EQ(meta["trajectory"], "handheld");
  // Nothing else next to the output (no temporaries).
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(tmp.path())) ++entries;
  EXPECT_EQ(entries, 1);
}

TEST(CliSynth, StereoWritesKittiLayout) {
  TempDir tmp;
  const fs::path out = tmp / "kitti";
  const auto r = run_cli({"synth", "--out", out.string(), "--frames", "3", "--stereo", "--width", "160",
                          "--height", "120"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(count_data_lines(out / "times.txt"), 3);
  EXPECT_EQ(count_data_lines(out / "poses.txt"), 3);
  EXPECT_EQ(count_data_lines(out / "calib.txt"), 4);
  EXPECT_TRUE(fs::is_regular_file(out / "image_1" / "000002.png"));
}

TEST(CliSynth, BadArgumentsFailWithAClearMessage) {
  TempDir tmp;
  const fs::path out = tmp / "seq";
  auto r = run_cli({"synth", "--out", out.string(), "--frames", "0"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--frames"), std::string::npos) << r.err;
  r = run_cli({"synth", "--out", out.string(), "--people", "-2"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--people"), std::string::npos) << r.err;
  r = run_cli({"synth", "--out", out.string(), "--trajectory", "zigzag"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("zigzag"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));

  fs::create_directories(out);
  crowdslam::test::write_text(out / "precious.txt", "keep");
  r = run_cli({"synth", "--out", out.string(), "--frames", "2", "--width", "64", "--height", "48"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--force"), std::string::npos) << r.err;
  EXPECT_EQ(read_text(out / "precious.txt"), "keep");
  r = run_cli({"synth", "--out", out.string(), "--frames", "2", "--width", "64", "--height", "48", "--force"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(out / "precious.txt"));
  EXPECT_EQ(count_data_lines(out / "rgb.txt"), 2);
}

}  // namespace
