// End-to-end stereo: a synthetic KITTI-layout stereo sequence against its exact ground truth, and the
// EuRoC V1_01 clip (raw pairs rectified with config/EuRoC.yaml, or from its sensor.yaml).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "crowdslam/io/dataset.h"
#include "crowdslam/io/settings.h"
#include "crowdslam/io/trajectory.h"
#include "crowdslam/synth/options.h"
#include "crowdslam/synth/writer.h"
#include "crowdslam/run/run_sequence.h"
#include "crowdslam/system/system.h"
#include "test_support.h"

using namespace crowdslam;

TEST(RunStereo, SyntheticStereoSequenceTrackedWithinOneCentimetre) {
  test::TempDir tmp;
  synth::SynthOptions synth_options;
  synth_options.frames = 90;
  synth_options.width = 320;  // small images keep the test fast (rendering dominates)
  synth_options.height = 240;
  synth_options.trajectory = synth::TrajectoryKind::kLine;
  synth_options.stereo = true;
  synth::write_sequence(synth_options, tmp / "seq");

  run::RunOptions options;
  options.dataset = (tmp / "seq").string();  // sensor detected: KITTI layout with image_1
  options.out_dir = (tmp / "out").string();
  options.sequential = true;
  options.progress = false;
  options.people_filter = false;
  const auto summary = run::run_sequence(options);
  EXPECT_EQ(summary.json["sensor"].get<std::string>(), "stereo");
  EXPECT_EQ(summary.frames, 90u);
  EXPECT_EQ(summary.tracked, 90u);  // initialised from the first pair, like RGB-D
  ASSERT_TRUE(summary.ate_rmse_m.has_value());
  EXPECT_LT(*summary.ate_rmse_m, 0.01);
  // About half the keypoints find a stereo partner (the rest are not detected in the right image).
  for (const auto& f : summary.json["frames"]) {
    EXPECT_GT(f["stereo_matches"].get<int>(), f["keypoints"].get<int>() / 3);
    EXPECT_LE(f["stereo_matches"].get<int>(), f["keypoints"].get<int>());
  }
  const auto trajectory = io::read_tum_trajectory((tmp / "out" / "CameraTrajectory.txt").string());
  EXPECT_EQ(trajectory.size(), 90u);
}

namespace {
run::RunSummary run_euroc(const test::TempDir& tmp, const std::string& settings, bool people_filter) {
  run::RunOptions options;
  options.dataset = test::shared_data("euroc_v101_micro").string();
  options.settings_path = settings;
  options.out_dir = (tmp / "out").string();
  options.sequential = true;
  options.progress = false;
  options.people_filter = people_filter;
  return run::run_sequence(options);
}
}  // namespace

TEST(RunStereo, EurocMicroAllFramesTrackedWithinTwoCentimetres) {
  CROWDSLAM_REQUIRE_SHARED("euroc_v101_micro");
  test::TempDir tmp;
  const auto summary = run_euroc(tmp, (test::source_dir() / "config" / "EuRoC.yaml").string(), true);
  EXPECT_EQ(summary.frames, 95u);
  EXPECT_EQ(summary.tracked, 95u);
  ASSERT_TRUE(summary.ate_rmse_m.has_value());
  EXPECT_LT(*summary.ate_rmse_m, 0.02);
  // Ground truth covers 74 of the image stamps (it starts about 1 s after the first image).
  EXPECT_GE(summary.json["accuracy"]["ate_pairs"].get<int>(), 70);
}

TEST(RunStereo, EurocRectificationFromSensorYamlWhenSettingsHaveNoBlocks) {
  CROWDSLAM_REQUIRE_SHARED("euroc_v101_micro");
  test::TempDir tmp;
  // config/EuRoC.yaml without its LEFT/RIGHT blocks: rectified from the dataset's sensor.yaml instead.
  std::string text = test::read_text(test::source_dir() / "config" / "EuRoC.yaml");
  const auto begin = text.find("LEFT.height");
  const auto end = text.find("# Person detector");
  ASSERT_NE(begin, std::string::npos);
  ASSERT_NE(end, std::string::npos);
  text.erase(begin, end - begin);
  test::write_text(tmp / "settings.yaml", text);
  const auto summary = run_euroc(tmp, (tmp / "settings.yaml").string(), false);
  EXPECT_EQ(summary.tracked, 95u);
  ASSERT_TRUE(summary.ate_rmse_m.has_value());
  EXPECT_LT(*summary.ate_rmse_m, 0.02);
}

TEST(RunStereo, PeopleFilterDropsLeftKeypointsInsideBoxes) {
  test::TempDir tmp;
  synth::SynthOptions synth_options;
  synth_options.frames = 40;
  synth_options.width = 320;
  synth_options.height = 240;
  synth_options.people = 3;
  synth_options.stereo = true;
  synth::write_sequence(synth_options, tmp / "seq");

  auto dataset = io::open_dataset((tmp / "seq").string());
  io::Settings settings = io::load_settings((tmp / "seq" / "settings.yaml").string(), io::SensorKind::kStereo);
  settings.people_filter.mode = "paper";
  system::SystemOptions options;
  options.sensor = io::SensorKind::kStereo;
  options.sequential = true;
  options.detections_file = (tmp / "seq" / "people_gt.txt").string();
  options.record_keypoints = true;
  system::System slam(settings, options);
  const float margin = static_cast<float>(settings.people_filter.margin_px);
  int frames_with_removal = 0;
  while (auto frame = dataset->next()) {
    const auto r = slam.track(frame->images, frame->info.timestamp_s);
    EXPECT_EQ(r.kept_keypoints.size() + r.removed_keypoints.size(), static_cast<size_t>(r.keypoints_before_filter));
    EXPECT_EQ(r.keypoints, static_cast<int>(r.kept_keypoints.size()));
    EXPECT_LE(r.stereo_matches, r.keypoints);
    for (const auto& k : r.kept_keypoints) {
      for (const auto& b : r.boxes) {
        const cv::Rect2f grown(b.box.x - margin, b.box.y - margin, b.box.width + 2 * margin, b.box.height + 2 * margin);
        EXPECT_FALSE(grown.contains(k.pt)) << "frame " << r.index;
      }
    }
    if (!r.removed_keypoints.empty()) ++frames_with_removal;
    if (r.boxes.empty()) {
      EXPECT_TRUE(r.removed_keypoints.empty());
    }
  }
  EXPECT_GT(frames_with_removal, 5);
}

// PeopleFilter.right_image: "boxes" also drops the stereo match of a kept left keypoint whose right
// coordinate falls in a person box (boxes of the left image, unshifted); "matched" never does.
TEST(RunStereo, RightImageBoxesModeDropsStereoMatchesInBoxes) {
  test::TempDir tmp;
  synth::SynthOptions synth_options;
  synth_options.frames = 30;
  synth_options.width = 320;
  synth_options.height = 240;
  synth_options.people = 3;
  synth_options.stereo = true;
  synth::write_sequence(synth_options, tmp / "seq");

  auto run = [&](const std::string& right_image) {
    auto dataset = io::open_dataset((tmp / "seq").string());
    io::Settings settings = io::load_settings((tmp / "seq" / "settings.yaml").string(), io::SensorKind::kStereo);
    settings.people_filter.right_image = right_image;
    system::SystemOptions options;
    options.sensor = io::SensorKind::kStereo;
    options.sequential = true;
    options.detections_file = (tmp / "seq" / "people_gt.txt").string();
    system::System slam(settings, options);
    int removed = 0;
    int matches = 0;
    while (auto frame = dataset->next()) {
      const auto r = slam.track(frame->images, frame->info.timestamp_s);
      if (r.boxes.empty()) {
        EXPECT_EQ(r.right_keypoints_removed, 0);
      }
      removed += r.right_keypoints_removed;
      matches += r.stereo_matches;
    }
    return std::make_pair(removed, matches);
  };
  const auto matched = run("matched");
  const auto boxes = run("boxes");
  EXPECT_EQ(matched.first, 0);
  EXPECT_GT(boxes.first, 0);
  // Each removal turns one stereo keypoint into a monocular one.
  EXPECT_LT(boxes.second, matched.second);
}
