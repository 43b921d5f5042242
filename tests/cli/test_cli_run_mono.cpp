// `crowdslam run --sensor mono` on sequences that cannot initialise a monocular map (static camera,
// textureless images): the run completes, every frame is not_initialized, the outputs say so, and a
// warning explains why. And an RGB-D sequence run as monocular records the sensor and Sim3 alignment.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "test_support.h"

using crowdslam::test::run_cli;
using crowdslam::test::TempDir;

namespace {

std::filesystem::path synth_sequence(const TempDir& dir, int frames) {
  const auto seq = dir / "seq";
  const auto r = run_cli({"-q", "synth", "--out", seq.string(), "--frames", std::to_string(frames), "--width",
                          "320", "--height", "240"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return seq;
}

// Replaces every colour image of a TUM-layout sequence by `image` (written as PNG under each name).
void overwrite_colour(const std::filesystem::path& seq, const cv::Mat& image) {
  for (const auto& entry : std::filesystem::directory_iterator(seq / "rgb")) {
    ASSERT_TRUE(cv::imwrite(entry.path().string(), image));
  }
}

nlohmann::json read_run_json(const std::filesystem::path& out) {
  return nlohmann::json::parse(crowdslam::test::read_text(out / "run.json"));
}

void expect_never_initialised(const std::filesystem::path& seq, const std::filesystem::path& out) {
  // A run that tracks nothing is an error unless --allow-untracked.
  const auto refused = run_cli({"-q", "run", "--dataset", seq.string(), "--out", out.string() + "_refused", "--sensor",
                                "mono", "--no-people-filter", "--sequential", "--vocabulary", "none"});
  EXPECT_EQ(refused.exit_code, 1) << refused.err;
  const auto r = run_cli({"-q", "run", "--dataset", seq.string(), "--out", out.string(), "--sensor", "mono",
                          "--no-people-filter", "--sequential", "--vocabulary", "none", "--allow-untracked"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string log = r.err;  // logs go to stderr
  EXPECT_NE(log.find("never initialised"), std::string::npos) << log;
  const auto doc = read_run_json(out);
  EXPECT_EQ(doc["sensor"], "monocular");
  EXPECT_TRUE(doc["summary"]["init_frame"].is_null());
  EXPECT_EQ(doc["summary"]["tracked_frames"], 0);
  EXPECT_EQ(doc["summary"]["keyframes"], 0);
  for (const auto& f : doc["frames"]) EXPECT_EQ(f["state"], "not_initialized");
  EXPECT_TRUE(crowdslam::test::read_text(out / "CameraTrajectory.txt").find_first_of("0123456789") ==
              std::string::npos);
}

}  // namespace

TEST(CliRunMono, StaticCameraNeverInitialises) {
  TempDir dir;
  const auto seq = synth_sequence(dir, 8);
  const cv::Mat first = cv::imread((seq / "rgb" / "000000.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(first.empty());
  overwrite_colour(seq, first);
  expect_never_initialised(seq, dir / "out");
}

TEST(CliRunMono, TexturelessImagesNeverInitialise) {
  TempDir dir;
  const auto seq = synth_sequence(dir, 6);
  overwrite_colour(seq, cv::Mat(240, 320, CV_8UC3, cv::Scalar(90, 120, 150)));
  expect_never_initialised(seq, dir / "out");
}
