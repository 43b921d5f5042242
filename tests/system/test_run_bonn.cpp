// End-to-end smoke test on real data: the first 200 frames of Bonn rgbd_bonn_crowd (RGB-D, no people
// filter), sequential mode so the result is reproducible.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "crowdslam/io/trajectory.h"
#include "crowdslam/run/run_sequence.h"
#include "crowdslam/util/error.h"
#include "test_support.h"

using namespace crowdslam;

TEST(RunBonn, First200FramesTrackedAccurately) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  test::TempDir out;
  run::RunOptions options;
  options.dataset = test::shared_data("bonn_crowd").string();
  options.settings_path = (test::source_dir() / "config" / "Bonn.yaml").string();
  options.out_dir = (out / "run").string();
  options.sequential = true;
  options.max_frames = 200;
  options.progress = false;
  const auto summary = run::run_sequence(options);

  EXPECT_EQ(summary.frames, 200u);
  EXPECT_GE(summary.tracked_percent, 95.0);
  ASSERT_TRUE(summary.ate_rmse_m.has_value());
  // The first 200 frames are mostly static background with people at the side: a static-world SLAM
  // stays within a few centimetres here (the crowded part comes later).
  EXPECT_LT(*summary.ate_rmse_m, 0.05);

  const auto trajectory = io::read_tum_trajectory((out / "run" / "CameraTrajectory.txt").string());
  EXPECT_EQ(trajectory.size(), summary.tracked);
  const auto keyframes = io::read_tum_trajectory((out / "run" / "KeyFrameTrajectory.txt").string());
  EXPECT_GE(keyframes.size(), 2u);
  EXPECT_LT(keyframes.size(), trajectory.size());
  const auto doc = nlohmann::json::parse(test::read_text(out / "run" / "run.json"));
  EXPECT_EQ(doc["frames"].size(), 200u);
  EXPECT_EQ(doc["summary"]["tracked_frames"].get<size_t>(), summary.tracked);
  EXPECT_TRUE(doc["frames"][0].contains("extraction_ms"));
}

TEST(RunBonn, MissingSettingsIsAClearErrorAndWritesNothing) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  test::TempDir out;
  run::RunOptions options;
  options.dataset = test::shared_data("bonn_crowd").string();
  options.settings_path = (out / "nope.yaml").string();
  options.out_dir = (out / "run").string();
  try {
    run::run_sequence(options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("nope.yaml"), std::string::npos);
  }
  EXPECT_FALSE(std::filesystem::exists(out / "run"));
}
