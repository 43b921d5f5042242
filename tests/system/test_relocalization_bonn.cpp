// Relocalisation fixture (issue 5): Bonn rgbd_bonn_crowd frames 0..399, then 3 black frames (camera
// covered), then frames 150..249, as one TUM-layout sequence with new stamps 1/30 s apart (the lists point
// at the shared images; only the black frame is written). Tracking is lost on the black frames, and the
// camera has "jumped" back 250 frames when the view returns: the frame must be relocalised against the
// map of the first part within 5 frames, with poses that agree with the ground truth (aligned on the first
// 400 frames) within 5 cm. Uses the default vocabulary; skipped without it.
//
// Without the black frames the jump alone does not lose tracking: this room-scale sequence moves little
// (frame 150 is 5 cm and 24 degrees from frame 399), so bag-of-words matching against the reference
// keyframe recovers the pose at once, and relocalisation would not be exercised.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "crowdslam/bow/vocabulary_path.h"
#include "crowdslam/eval/ate.h"
#include "crowdslam/io/associate.h"
#include "crowdslam/io/trajectory.h"
#include "crowdslam/io/tum_dataset.h"
#include "crowdslam/run/run_sequence.h"
#include "test_support.h"

using namespace crowdslam;

namespace {

constexpr size_t kFirstPart = 400;  // original frames 0..399
constexpr size_t kBlackout = 3;     // then black frames
constexpr size_t kJumpTo = 150;     // then original frames 150..249
constexpr size_t kSecondPart = 100;
constexpr size_t kReturn = kFirstPart + kBlackout;  // fixture index of the first frame after the jump
constexpr size_t kNone = static_cast<size_t>(-1);
constexpr double kStart_s = 1000.0;
constexpr double kPeriod_s = 1.0 / 30.0;

double stamp_of(size_t k) { return kStart_s + static_cast<double>(k) * kPeriod_s; }

// Writes the fixture into `dir`; returns its ground truth (fixture stamps).
io::Trajectory write_fixture(const std::filesystem::path& dir) {
  const auto bonn = io::open_tum_dataset(test::shared_data("bonn_crowd").string());
  const auto& frames = bonn->frames();
  // Ground truth of each original frame (TUM association, 20 ms).
  const io::Trajectory& gt = bonn->ground_truth();
  std::vector<double> frame_stamps, gt_stamps;
  for (const auto& f : frames) frame_stamps.push_back(f.timestamp_s);
  for (const auto& p : gt) gt_stamps.push_back(p.timestamp_s);
  std::map<size_t, geometry::SE3> gt_of_frame;
  for (const auto& a : io::associate_timestamps(frame_stamps, gt_stamps)) {
    gt_of_frame[a.first_index] = gt[a.second_index].world_from_cam;
  }

  std::vector<size_t> original;
  for (size_t i = 0; i < kFirstPart; ++i) original.push_back(i);
  for (size_t i = 0; i < kBlackout; ++i) original.push_back(kNone);
  for (size_t i = kJumpTo; i < kJumpTo + kSecondPart; ++i) original.push_back(i);
  std::filesystem::create_directories(dir);
  const auto black_colour = dir / "black.png";
  const auto black_depth = dir / "black_depth.png";
  cv::imwrite(black_colour.string(), cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(0)));
  cv::imwrite(black_depth.string(), cv::Mat(480, 640, CV_16UC1, cv::Scalar::all(0)));
  std::ofstream rgb(dir / "rgb.txt"), depth(dir / "depth.txt");
  rgb << "# color images\n# timestamp filename\n";
  depth << "# depth maps\n# timestamp filename\n";
  rgb.precision(17);
  depth.precision(17);
  io::Trajectory fixture_gt;
  for (size_t k = 0; k < original.size(); ++k) {
    if (original[k] == kNone) {
      rgb << stamp_of(k) << " " << black_colour.string() << "\n";
      depth << stamp_of(k) << " " << black_depth.string() << "\n";
      continue;
    }
    const auto& f = frames.at(original[k]);
    rgb << stamp_of(k) << " " << std::filesystem::absolute(f.colour_path).string() << "\n";
    depth << stamp_of(k) << " " << std::filesystem::absolute(f.depth_path).string() << "\n";
    if (const auto it = gt_of_frame.find(original[k]); it != gt_of_frame.end()) {
      fixture_gt.push_back({stamp_of(k), it->second});
    }
  }
  io::write_tum_trajectory((dir / "groundtruth.txt").string(), fixture_gt);
  return fixture_gt;
}

size_t fixture_index(double stamp) { return static_cast<size_t>(std::lround((stamp - kStart_s) / kPeriod_s)); }

}  // namespace

TEST(RelocalizationBonn, JumpBackIsRelocalisedWithinFiveFramesAndFiveCentimetres) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const std::string vocabulary = bow::default_vocabulary_path();
  if (!std::filesystem::is_regular_file(vocabulary)) {
    GTEST_SKIP() << "default vocabulary " << vocabulary
                 << " missing (scripts/build_vocabulary.sh builds it; CROWDSLAM_VOCABULARY overrides)";
  }
  test::TempDir tmp;
  const auto dataset = tmp / "jump";
  const io::Trajectory gt = write_fixture(dataset);
  ASSERT_GT(gt.size(), 450u);

  // As the Bonn end-to-end test: default options (people filter), sequential for reproducibility.
  run::RunOptions options;
  options.dataset = dataset.string();
  options.settings_path = (test::source_dir() / "config" / "Bonn.yaml").string();
  options.out_dir = (tmp / "out").string();
  options.sequential = true;
  options.progress = false;
  options.vocabulary = vocabulary;
  const auto summary = run::run_sequence(options);
  ASSERT_EQ(summary.frames, kReturn + kSecondPart);

  const auto doc = nlohmann::json::parse(test::read_text(tmp / "out" / "run.json"));
  ASSERT_FALSE(doc["vocabulary"].is_null());
  EXPECT_EQ(doc["summary"]["map_resets"].get<int>(), 0);
  const auto& frames = doc["frames"];
  // The first part is tracked throughout.
  size_t tracked_first = 0;
  for (size_t k = 0; k < kFirstPart; ++k) tracked_first += frames[k]["state"] == "ok";
  EXPECT_GE(tracked_first, kFirstPart - 5);
  // Lost while the camera is covered; relocalised after the jump.
  for (size_t k = kFirstPart; k < kReturn; ++k) EXPECT_EQ(frames[k]["state"], "lost") << "frame " << k;
  size_t relocalised_at = frames.size();
  for (size_t k = kReturn; k < frames.size(); ++k) {
    if (frames[k]["state"] == "ok") {
      relocalised_at = k;
      break;
    }
  }
  ASSERT_LT(relocalised_at, frames.size()) << "never relocalised";
  const size_t frames_to_relocalise = relocalised_at - kReturn;
  std::printf("view back at fixture frame %zu (original frame %zu): relocalised at frame %zu (%zu frames later, "
              "method %s, %d inliers)\n",
              kReturn, kJumpTo, relocalised_at, frames_to_relocalise,
              frames[relocalised_at]["method"].get<std::string>().c_str(),
              frames[relocalised_at]["tracked_points"].get<int>());
  EXPECT_LE(frames_to_relocalise, 5u);
  EXPECT_EQ(frames[relocalised_at]["method"], "relocalization");
  size_t tracked_after = 0;
  for (size_t k = relocalised_at; k < frames.size(); ++k) tracked_after += frames[k]["state"] == "ok";
  EXPECT_GE(tracked_after, (frames.size() - relocalised_at) * 9 / 10);

  // Poses after the jump in the frame of the ground truth, aligned on the first part only.
  const auto estimate = io::read_tum_trajectory((tmp / "out" / "CameraTrajectory.txt").string());
  io::Trajectory gt_first, estimate_first, estimate_after;
  for (const auto& p : gt) {
    if (fixture_index(p.timestamp_s) < kFirstPart) gt_first.push_back(p);
  }
  for (const auto& p : estimate) {
    (fixture_index(p.timestamp_s) < kFirstPart ? estimate_first : estimate_after).push_back(p);
    EXPECT_FALSE(fixture_index(p.timestamp_s) >= kFirstPart && fixture_index(p.timestamp_s) < kReturn);
  }
  const auto first = eval::evaluate_ate(gt_first, estimate_first, eval::AteOptions{});
  const auto aligned_after = eval::apply_alignment(estimate_after, first.alignment, 1.0);
  std::map<size_t, geometry::Vec3> gt_position;
  for (const auto& p : gt) gt_position[fixture_index(p.timestamp_s)] = p.world_from_cam.translation();
  std::vector<double> errors;
  for (const auto& p : aligned_after) {
    const auto it = gt_position.find(fixture_index(p.timestamp_s));
    if (it == gt_position.end()) continue;
    errors.push_back((p.world_from_cam.translation() - it->second).norm());
  }
  ASSERT_GE(errors.size(), kSecondPart * 9 / 10 - frames_to_relocalise);
  std::vector<double> sorted = errors;
  std::sort(sorted.begin(), sorted.end());
  std::printf("first part ATE %.4f m; after the jump %zu poses: first %.4f m, median %.4f m, max %.4f m\n",
              first.translation_error_m.rmse, errors.size(), errors.front(), sorted[sorted.size() / 2],
              sorted.back());
  EXPECT_LT(errors.front(), 0.05);  // the relocalised pose itself
  EXPECT_LT(sorted.back(), 0.05);   // and every pose tracked after it
}
