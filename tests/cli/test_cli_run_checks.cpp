// `crowdslam run` checks that need both the dataset and the settings, before the first frame (issue 10,
// findings 6, 7, 12): a dataset that cannot feed the camera the settings describe, images of another
// size than Camera.width/height, a bad --filter-mode. Each is one line naming what is wrong, exit 1, and
// no output directory.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "run_test_helpers.h"

using namespace crowdslam::test;
namespace fs = std::filesystem;

namespace {
void expect_refused(const CliResult& r, const fs::path& out, const std::vector<std::string>& needles) {
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  for (const auto& needle : needles) EXPECT_NE(r.err.find(needle), std::string::npos) << needle << " in " << r.err;
  EXPECT_FALSE(fs::exists(out));
}
}  // namespace

TEST(CliRunChecks, RgbdSettingsOnADatasetWithoutDepthIsAnErrorUnlessMono) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  TempDir dir;
  // A TUM copy without depth.txt: the lists point at the shared images.
  const auto bonn = shared_data("bonn_crowd");
  const auto copy = dir / "no_depth";
  fs::create_directories(copy);
  fs::create_symlink(bonn / "rgb", copy / "rgb");
  fs::copy_file(bonn / "rgb.txt", copy / "rgb.txt");
  fs::copy_file(bonn / "groundtruth.txt", copy / "groundtruth.txt");
  const auto settings = (source_dir() / "config" / "Bonn.yaml").string();
  const auto out = dir / "out";
  const auto r = run_cli({"-q", "run", "--dataset", copy.string(), "--settings", settings, "--out", out.string()});
  expect_refused(r, out, {"no_depth", "depth.txt", "Bonn.yaml", "DepthMapFactor", "--sensor mono"});
  // On purpose: monocular on the colour images.
  const auto mono = run_cli({"-q", "run", "--dataset", copy.string(), "--settings", settings, "--out", out.string(),
                             "--sensor", "mono", "--frames", "30", "--allow-untracked", "--no-people-filter"});
  EXPECT_EQ(mono.exit_code, 0) << mono.err;
  EXPECT_EQ(read_json(out / "run.json")["sensor"], "monocular");
}

TEST(CliRunChecks, StereoSettingsOnEurocWithoutCam1IsAnErrorUnlessMono) {
  CROWDSLAM_REQUIRE_SHARED("euroc_v101_micro");
  TempDir dir;
  const auto euroc = shared_data("euroc_v101_micro");
  const auto copy = dir / "left_only";
  fs::create_directories(copy / "mav0");
  fs::create_symlink(euroc / "mav0" / "cam0", copy / "mav0" / "cam0");
  const auto settings = (source_dir() / "config" / "EuRoC.yaml").string();
  const auto out = dir / "out";
  const auto r = run_cli({"-q", "run", "--dataset", copy.string(), "--settings", settings, "--out", out.string()});
  expect_refused(r, out, {"left_only", "cam1", "EuRoC.yaml", "--sensor mono"});
  const auto explicit_stereo = run_cli(
      {"-q", "run", "--dataset", copy.string(), "--settings", settings, "--out", out.string(), "--sensor", "stereo"});
  expect_refused(explicit_stereo, out, {"--sensor stereo", "cam1"});
}

TEST(CliRunChecks, ImagesOfAnotherSizeThanTheSettingsAreAnErrorNamingBoth) {
  TempDir dir;
  const auto seq = synth_small(dir, 6);  // 320x240
  const auto out = dir / "out";
  const auto r = run_cli({"-q", "run", "--dataset", seq.string(), "--settings",
                          (source_dir() / "config" / "Bonn.yaml").string(), "--out", out.string(), "--no-people-filter"});
  expect_refused(r, out, {"000000.png", "320x240", "640x480", "Bonn.yaml", "Camera.width"});
}

TEST(CliRunChecks, AFrameOfAnotherSizeMidSequenceNamesTheColourFile) {
  TempDir dir;
  const auto seq = synth_small(dir, 12);
  const auto other = synth_small(dir, 6, "other", {"--width", "400", "--height", "300"});
  fs::copy_file(other / "rgb" / "000005.png", seq / "rgb" / "000007.png", fs::copy_options::overwrite_existing);
  fs::copy_file(other / "depth" / "000005.png", seq / "depth" / "000007.png", fs::copy_options::overwrite_existing);
  const auto out = dir / "out";
  const auto r = run_cli({"-q", "run", "--dataset", seq.string(), "--out", out.string(), "--no-people-filter"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("rgb/000007.png"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("400x300"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("depth/000007.png"), std::string::npos) << r.err;
  // The frames before it are kept.
  EXPECT_EQ(read_json(out / "run.json")["summary"]["frames"], 7);
}

TEST(CliRunChecks, BadFilterModeNamesTheOptionNotTheSettingsFile) {
  TempDir dir;
  const auto seq = synth_small(dir, 4);
  const auto out = dir / "out";
  const auto r = run_cli({"-q", "run", "--dataset", seq.string(), "--out", out.string(), "--filter-mode", "bogus"});
  expect_refused(r, out, {"--filter-mode", "bogus"});
  EXPECT_EQ(r.err.find("settings.yaml"), std::string::npos) << r.err;
}

TEST(CliRunChecks, ShortRunSaysWhichAccuracyFigureIsMissing) {
  TempDir dir;
  const auto seq = synth_small(dir, 20);  // 0.67 s: an ATE, but no RPE pair 1 s apart
  const auto out = dir / "out";
  const auto r = run_cli({"run", "--dataset", seq.string(), "--out", out.string(), "--no-people-filter", "--sequential"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("ATE RMSE"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("RPE not evaluated (the ATE is)"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("accuracy not evaluated"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("ground truth ground truth"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("groundtruth.txt"), std::string::npos) << r.err;  // the file is named instead
  const auto accuracy = read_json(out / "run.json")["accuracy"];
  EXPECT_TRUE(accuracy.contains("ate_rmse_m"));
  EXPECT_TRUE(accuracy.contains("rpe_error"));
}
