// End-to-end: keypoints in person boxes taken back by the static map (tracking/box_keypoints.cpp). A box
// that is a false positive covering nearly the whole image of a static synthetic room costs no tracking
// with PeopleFilter.static_in_boxes "always"; with the RGB-D default (off) the same box loses the camera.
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

// `static_in_boxes` empty: the settings' default ("monocular": not used in this RGB-D run).
run::RunSummary run_room(const std::filesystem::path& dataset, const std::filesystem::path& out,
                         const std::string& static_in_boxes) {
  const auto settings = out.string() + ".yaml";
  {
    std::ifstream in(dataset / "settings.yaml");
    std::ofstream copy(settings);
    copy << in.rdbuf() << "\n";
    if (!static_in_boxes.empty()) copy << "PeopleFilter.static_in_boxes: \"" << static_in_boxes << "\"\n";
  }
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

  const auto with_check = run_room(dataset, tmp / "on", "always");
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

  // The same box with the default for RGB-D (box keypoints with depth only in monocular): the filtered
  // frames have too little left and the camera is lost.
  const auto without = run_room(dataset, tmp / "default", "");
  EXPECT_EQ(without.json["people_filter"]["static_in_boxes"], "monocular");
  EXPECT_LT(without.tracked, static_cast<size_t>(kFrames) - 5);
  EXPECT_EQ(without.json["people_filter"]["frames_with_box_matches"].get<int>(), 0);
}
