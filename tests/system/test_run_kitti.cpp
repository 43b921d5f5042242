// Monocular SLAM on real forward motion (issue 11): KITTI odometry 07, the first 100 frames (a car
// accelerating to 8.5 m/s through a town), in sequential mode so the run is reproducible. The map is
// initialised once and never reset, every frame is tracked (those before the initialisation localised in
// the new map afterwards), and the Sim3 ATE
// stays within 0.65 % of the 54 m travelled (the target for the threaded mode is 0.5 %, 0.27 m:
// not met yet, see docs/RESULTS.md).
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "crowdslam/run/run_sequence.h"
#include "test_support.h"

using namespace crowdslam;

TEST(RunKitti, MonocularForwardMotionInitialisesOnceAndKeepsTrack) {
  CROWDSLAM_REQUIRE_SHARED("kitti07_head");
  test::TempDir tmp;
  run::RunOptions options;
  options.dataset = test::shared_data("kitti07_head").string();
  options.settings_path = (test::source_dir() / "config" / "KITTI04-12.yaml").string();
  options.out_dir = (tmp / "out").string();
  options.sensor = io::SensorKind::kMonocular;
  options.sequential = true;
  options.progress = false;
  options.people_filter = false;
  const auto summary = run::run_sequence(options);
  ASSERT_TRUE(summary.init_frame.has_value());
  EXPECT_LE(*summary.init_frame, 10u);
  EXPECT_EQ(summary.json["summary"]["map_resets"], 0);
  EXPECT_EQ(summary.segments.size(), 1u);
  // From the initialisation on (and its reference frame), every frame; and the frames the initializer saw
  // before it, localised in the new map afterwards (the car barely moves there: all of them).
  // (The initializer's reference frame, the first keyframe, is one of them.)
  EXPECT_EQ(summary.frames_localized_before_init, *summary.init_frame);
  EXPECT_EQ(summary.tracked, summary.frames - *summary.init_frame + summary.frames_localized_before_init);
  EXPECT_EQ(summary.tracked, summary.frames);
  const auto& frames = summary.json["frames"];
  for (size_t i = 0; i < *summary.init_frame; ++i) {
    EXPECT_EQ(frames[i]["state"], "not_initialized") << i;  // its own report, made before the map existed
    EXPECT_TRUE(frames[i]["localized_after_init"].get<bool>()) << i;
  }
  ASSERT_TRUE(summary.ate_rmse_m.has_value());
  EXPECT_LT(*summary.ate_rmse_m, 0.35);
  std::printf("[ measured ] kitti07_head sequential: %zu/%zu tracked, ATE %.3f m, %d keyframes\n", summary.tracked,
              summary.frames, *summary.ate_rmse_m, summary.json["summary"]["keyframes"].get<int>());
}

namespace {
std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Runs the dataset twice in sequential mode and returns both runs' camera and keyframe trajectories.
std::array<std::string, 4> two_sequential_runs(run::RunOptions options, const test::TempDir& tmp) {
  std::array<std::string, 4> files;
  for (int k = 0; k < 2; ++k) {
    options.out_dir = (tmp / ("out" + std::to_string(k))).string();
    const auto summary = run::run_sequence(options);
    EXPECT_GT(summary.tracked, 0u);
    files[2 * k] = read_file(std::filesystem::path(options.out_dir) / "CameraTrajectory.txt");
    files[2 * k + 1] = read_file(std::filesystem::path(options.out_dir) / "KeyFrameTrajectory.txt");
  }
  return files;
}
}  // namespace

// Issue 11: --sequential stays reproducible, byte for byte, on real data: monocular (two-view
// initialisation, RANSAC) and RGB-D with the people detector.
TEST(RunKitti, SequentialRunsGiveByteIdenticalTrajectories) {
  CROWDSLAM_REQUIRE_SHARED("kitti07_head");
  test::TempDir tmp;
  run::RunOptions options;
  options.dataset = test::shared_data("kitti07_head").string();
  options.settings_path = (test::source_dir() / "config" / "KITTI04-12.yaml").string();
  options.sensor = io::SensorKind::kMonocular;
  options.sequential = true;
  options.progress = false;
  options.people_filter = false;
  options.max_frames = 40;
  const auto files = two_sequential_runs(options, tmp);
  EXPECT_GT(files[0].size(), 1000u);
  EXPECT_TRUE(files[0] == files[2]) << "camera trajectories differ between two sequential runs";
  EXPECT_TRUE(files[1] == files[3]) << "keyframe trajectories differ between two sequential runs";
}

TEST(RunKitti, SequentialRgbdRunsWithThePeopleFilterGiveByteIdenticalTrajectories) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  test::TempDir tmp;
  run::RunOptions options;
  options.dataset = test::shared_data("bonn_crowd").string();
  options.settings_path = (test::source_dir() / "config" / "Bonn.yaml").string();
  options.sequential = true;
  options.progress = false;
  options.max_frames = 80;
  const auto files = two_sequential_runs(options, tmp);
  EXPECT_GT(files[0].size(), 1000u);
  EXPECT_TRUE(files[0] == files[2]) << "camera trajectories differ between two sequential runs";
  EXPECT_TRUE(files[1] == files[3]) << "keyframe trajectories differ between two sequential runs";
}
