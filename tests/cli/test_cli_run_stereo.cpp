// `crowdslam run` with stereo: sensor mismatches, unrectified input, a missing or mis-sized right image.
// Each is one line on stderr naming the problem, exit code 1, and no output directory (a bad right image
// in the middle of the sequence keeps the frames before it).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <regex>

#include "test_support.h"

using crowdslam::test::run_cli;
using crowdslam::test::TempDir;

namespace {
std::filesystem::path synth(const TempDir& dir, const std::string& name, bool stereo) {
  const auto seq = dir / name;
  std::vector<std::string> args{"-q", "synth", "--out", seq.string(), "--frames", "6", "--width", "320", "--height", "240"};
  if (stereo) args.push_back("--stereo");
  const auto r = run_cli(args);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return seq;
}

void expect_clean_failure(const crowdslam::test::CliResult& r, const std::filesystem::path& out,
                          const std::string& needle) {
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
}
}  // namespace

TEST(CliRunStereo, SensorThatTheDatasetCannotProvideIsAClearError) {
  TempDir dir;
  const auto rgbd = synth(dir, "rgbd", false);
  const auto stereo = synth(dir, "stereo", true);
  const auto out = dir / "out";
  expect_clean_failure(run_cli({"-q", "run", "--dataset", rgbd.string(), "--out", out.string(), "--sensor", "stereo",
                                "--no-people-filter"}),
                       out, "--sensor stereo needs a stereo dataset");
  expect_clean_failure(run_cli({"-q", "run", "--dataset", stereo.string(), "--out", out.string(), "--sensor", "rgbd",
                                "--no-people-filter"}),
                       out, "depth");
  // The detected sensor works.
  const auto ok = run_cli({"-q", "run", "--dataset", stereo.string(), "--out", out.string(), "--no-people-filter"});
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_TRUE(std::filesystem::exists(out / "CameraTrajectory.txt"));
}

TEST(CliRunStereo, DistortedCameraWithoutRectificationIsAClearError) {
  TempDir dir;
  const auto stereo = synth(dir, "stereo", true);
  std::string text = crowdslam::test::read_text(stereo / "settings.yaml");
  text = std::regex_replace(text, std::regex("Camera\\.k1: [^\n]*"), "Camera.k1: -0.2");
  crowdslam::test::write_text(dir / "distorted.yaml", text);
  const auto out = dir / "out";
  expect_clean_failure(run_cli({"-q", "run", "--dataset", stereo.string(), "--settings", (dir / "distorted.yaml").string(),
                                "--out", out.string(), "--no-people-filter"}),
                       out, "LEFT/RIGHT");
}

TEST(CliRunStereo, MissingOrMisSizedRightImageIsAClearError) {
  TempDir dir;
  const auto stereo = synth(dir, "stereo", true);
  const auto out = dir / "out";
  // A right image of another size in the middle of the sequence: an error naming it, after the frames
  // before it were tracked and written (run.json says "failed").
  const auto victim = stereo / "image_1" / "000003.png";
  cv::imwrite(victim.string(), cv::Mat(120, 160, CV_8UC3, cv::Scalar(0, 0, 0)));
  const auto mid = run_cli({"-q", "run", "--dataset", stereo.string(), "--out", out.string(), "--no-people-filter"});
  EXPECT_EQ(mid.exit_code, 1);
  EXPECT_NE(mid.err.find("image_1/000003.png"), std::string::npos) << mid.err;
  EXPECT_NE(crowdslam::test::read_text(out / "run.json").find("\"end_state\": \"failed: "), std::string::npos);
  std::filesystem::remove_all(out);
  // A missing right image: found when the dataset is opened, before any output.
  std::filesystem::remove(victim);
  expect_clean_failure(run_cli({"-q", "run", "--dataset", stereo.string(), "--out", out.string(), "--no-people-filter"}),
                       out, "000003.png");
}
