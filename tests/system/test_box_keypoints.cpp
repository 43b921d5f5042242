// End-to-end: a false-positive box covering nearly the whole image of a static synthetic room costs no
// tracking, two ways: keypoints in person boxes taken back by the static map (tracking/box_keypoints.cpp,
// PeopleFilter.static_in_boxes "always"), and the RGB-D default, the depth test that finds the box flat
// (people/box_depth.h). With neither (static_in_boxes "never", flat_box_margin_m 0) the same box loses the
// camera; with the default "auto" and no depth test, the frames the filter leaves too little are taken
// back with their box keypoints.
#include <gtest/gtest.h>

#include <fstream>

#include "crowdslam/run/run_sequence.h"
#include "crowdslam/synth/options.h"
#include "crowdslam/synth/writer.h"
#include "test_support.h"

using namespace crowdslam;

namespace {
constexpr int kFrames = 120;
constexpr int kFirstBoxFrame = 50;  // 0-based frames 50-61 carry the false positive
constexpr int kLastBoxFrame = 61;

// The default room without people, the loop at 1.3 m/s (120 frames), and a MOT file with one box
// covering 96 % of each side of the 640x480 image in frames kFirstBoxFrame-kLastBoxFrame.
std::filesystem::path make_room(const test::TempDir& tmp) {
  synth::SynthOptions options;
  options.frames = kFrames;
  options.seed = 1;
  const auto dir = tmp / "room";
  synth::write_sequence(options, dir);
  std::ofstream mot(dir / "false_positive.txt");
  for (int f = kFirstBoxFrame; f <= kLastBoxFrame; ++f) mot << f + 1 << ",1,13,10,614,461,0.9,-1,-1,-1\n";
  return dir;
}

// `static_in_boxes` empty: the settings' default ("auto": with depth, only for frames the filter fails).
// `flat_box_margin_m` < 0: the settings' default.
run::RunSummary run_room(const std::filesystem::path& dataset, const std::filesystem::path& out,
                         const std::string& static_in_boxes, double flat_box_margin_m = -1.0) {
  const auto settings = out.string() + ".yaml";
  std::string text = test::read_text(dataset / "settings.yaml") + "\n";
  if (!static_in_boxes.empty()) text += "PeopleFilter.static_in_boxes: \"" + static_in_boxes + "\"\n";
  // Box keypoints are what this test measures. With the default depth margin (0.5 m) the depth-mode
  // filter keeps the far half of the room under the box, the frames track more than box_check_below
  // points on it alone and box keypoints are not consulted (0.021 m against 0.006 m with 1 m).
  if (static_in_boxes == "always") text += "PeopleFilter.depth_margin_m: 1.0\n";
  if (flat_box_margin_m >= 0) {
    text += "PeopleFilter.flat_box_margin_m: " + std::to_string(flat_box_margin_m) + "\n";
  }
  test::write_text(settings, text);
  run::RunOptions options;
  options.dataset = dataset.string();
  options.settings_path = settings;
  options.out_dir = out.string();
  options.sequential = true;
  options.progress = false;
  options.allow_untracked = true;
  options.detections_file = (dataset / "false_positive.txt").string();
  return run::run_sequence(options);
}
}  // namespace

TEST(RunBoxKeypoints, AFalsePositiveOverNearlyTheWholeImageCostsNoTracking) {
  test::TempDir tmp;
  const auto dataset = make_room(tmp);

  // The depth test off, so that the box reaches the filter and its keypoints the static map.
  const auto with_check = run_room(dataset, tmp / "on", "always", 0.0);
  EXPECT_EQ(with_check.tracked, static_cast<size_t>(kFrames));
  EXPECT_EQ(with_check.json["summary"]["map_resets"].get<int>(), 0);
  ASSERT_TRUE(with_check.ate_rmse_m.has_value());
  EXPECT_LT(*with_check.ate_rmse_m, 0.02);
  const auto& people = with_check.json["people_filter"];
  EXPECT_EQ(people["static_in_boxes"], "always");
  // Under the box the frame keeps almost no keypoint of its own: its tracked points are box keypoints
  // that matched the map's static points and agreed with the pose.
  int frames_with_box_matches = 0;
  for (const auto& f : with_check.json["frames"]) {
    const int index = f["index"].get<int>();
    if (index < kFirstBoxFrame || index > kLastBoxFrame) {
      EXPECT_EQ(f["box_matches"].get<int>(), 0) << "frame " << index;
      continue;
    }
    EXPECT_EQ(f["state"], "ok") << "frame " << index;
    if (f["box_matches"].get<int>() > 0) ++frames_with_box_matches;
  }
  EXPECT_GE(frames_with_box_matches, kLastBoxFrame - kFirstBoxFrame);
  EXPECT_EQ(people["frames_with_box_matches"].get<int>(), frames_with_box_matches);

  // The RGB-D defaults: the box lies on the room's walls and furniture with nothing standing out of them,
  // so the depth test drops it and the frames keep their keypoints (box keypoints, "auto", are not needed).
  const auto defaults = run_room(dataset, tmp / "default", "");
  EXPECT_EQ(defaults.json["people_filter"]["static_in_boxes"], "auto");
  EXPECT_EQ(defaults.tracked, static_cast<size_t>(kFrames));
  EXPECT_EQ(defaults.json["summary"]["map_resets"].get<int>(), 0);
  ASSERT_TRUE(defaults.ate_rmse_m.has_value());
  EXPECT_LT(*defaults.ate_rmse_m, 0.02);
  EXPECT_EQ(defaults.json["people_filter"]["frames_with_box_matches"].get<int>(), 0);
  EXPECT_EQ(defaults.json["people_filter"]["flat_boxes"].get<int>(), kLastBoxFrame - kFirstBoxFrame + 1);
  for (const auto& f : defaults.json["frames"]) {
    const int index = f["index"].get<int>();
    const bool boxed = index >= kFirstBoxFrame && index <= kLastBoxFrame;
    EXPECT_EQ(f["flat_boxes"].get<int>(), boxed ? 1 : 0) << "frame " << index;
    EXPECT_EQ(f["person_boxes"].get<int>(), 0) << "frame " << index;
  }

  // Neither: the filtered frames have too little left and the camera is lost.
  const auto neither = run_room(dataset, tmp / "neither", "never", 0.0);
  EXPECT_LT(neither.tracked, static_cast<size_t>(kFrames) - 5);
  EXPECT_EQ(neither.json["people_filter"]["flat_boxes"].get<int>(), 0);
  EXPECT_EQ(neither.json["people_filter"]["frames_with_box_matches"].get<int>(), 0);

  // The default box keypoints with depth ("auto"), the depth test off: the frames that fail on what the
  // filter leaves are taken back with their box keypoints, no box is released into the map, and no other
  // frame uses them.
  const auto rescue = run_room(dataset, tmp / "auto", "auto", 0.0);
  EXPECT_EQ(rescue.tracked, static_cast<size_t>(kFrames));
  EXPECT_EQ(rescue.json["summary"]["map_resets"].get<int>(), 0);
  ASSERT_TRUE(rescue.ate_rmse_m.has_value());
  EXPECT_LT(*rescue.ate_rmse_m, 0.02);
  int rescued = 0;
  for (const auto& f : rescue.json["frames"]) {
    const int index = f["index"].get<int>();
    EXPECT_EQ(f["static_boxes"].get<int>(), 0) << "frame " << index;
    if (f["box_matches"].get<int>() == 0) continue;
    // Box matches only where the filtered keypoints failed: the frame is reported rescued.
    EXPECT_EQ(f["method"], "motion+boxes") << "frame " << index;
    EXPECT_TRUE(index >= kFirstBoxFrame && index <= kLastBoxFrame) << "frame " << index;
    ++rescued;
  }
  EXPECT_GE(rescued, kLastBoxFrame - kFirstBoxFrame);
}
