#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>

#include "crowdslam/eval/rpe.h"
#include "crowdslam/util/error.h"

using namespace crowdslam;
using crowdslam::eval::DeltaUnit;
using crowdslam::eval::evaluate_rpe;
using crowdslam::eval::find_closest_index;
using crowdslam::eval::RpeOptions;
using crowdslam::eval::RpeResult;
using crowdslam::geometry::SE3;
using crowdslam::geometry::Vec3;
using crowdslam::io::Trajectory;

namespace {

constexpr double kTol = 1e-9;
constexpr double kPi = 3.14159265358979323846;

// Stamps first, first + step, ... (count of them).
std::vector<double> stamps(std::size_t count, double step, double first = 0.0) {
  std::vector<double> result;
  for (std::size_t k = 0; k < count; ++k) result.push_back(first + step * static_cast<double>(k));
  return result;
}

Trajectory sample(const std::vector<double>& times, const std::function<SE3(double)>& pose_at) {
  Trajectory trajectory;
  for (double t : times) trajectory.push_back({t, pose_at(t)});
  return trajectory;
}

// A fixed tilted orientation, so the relative motions are not expressed in the world axes.
const Eigen::Quaterniond kTilt(Eigen::AngleAxisd(0.6, Vec3(1.0, 1.0, -0.5).normalized()));

// Moves along world x at `speed` m/s with the fixed orientation.
std::function<SE3(double)> moving_along_x(double speed) {
  return [speed](double t) { return SE3(kTilt, Vec3(speed * t, 0.0, 0.0)); };
}

// Turns about world z at `rate` rad/s, at a fixed position.
std::function<SE3(double)> turning(double rate) {
  return [rate](double t) {
    return SE3(Eigen::Quaterniond(Eigen::AngleAxisd(rate * t, Vec3::UnitZ())), Vec3(0.5, -1.0, 2.0));
  };
}

void expect_error_message(const std::function<void()>& run, const std::vector<std::string>& needles) {
  try {
    run();
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    for (const auto& needle : needles)
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(FindClosestIndex, MatchesTheScriptsBinarySearch) {
  const std::vector<double> list{0.0, 1.0, 2.0, 3.0};
  EXPECT_EQ(find_closest_index(list, 2.0), 2u);
  EXPECT_EQ(find_closest_index(list, 0.9), 1u);
  EXPECT_EQ(find_closest_index(list, 2.2), 2u);
  EXPECT_EQ(find_closest_index(list, -5.0), 0u);
  EXPECT_EQ(find_closest_index(list, 99.0), 3u);
  // Tie at 1.5: the search probes index 2 first (|2 - 1.5| = 0.5), then index 1 (0.5, not smaller).
  EXPECT_EQ(find_closest_index(list, 1.5), 2u);
  // Tie at 0.5: index 0 is the starting guess (0.5); probes 2 (1.5), 1 (0.5, not smaller), 0 -> 0.
  EXPECT_EQ(find_closest_index(list, 0.5), 0u);
  EXPECT_EQ(find_closest_index({7.0}, 1.0), 0u);
}

TEST(Rpe, IdenticalTrajectoriesGiveZero) {
  const Trajectory gt = sample(stamps(31, 0.1), turning(0.3));
  const RpeResult r = evaluate_rpe(gt, gt, RpeOptions{});
  EXPECT_EQ(r.pairs.size(), 20u);  // 31 - 10 - 1 (see ScaleErrorPerSecond)
  EXPECT_NEAR(r.translation_error_m.max, 0.0, kTol);
  EXPECT_NEAR(r.rotation_error_deg.max, 0.0, 1e-6);  // arccos near 1 amplifies rounding
}

TEST(Rpe, TenPercentTooFastGivesPointOneMetrePerSecond) {
  // 51 poses, 10 Hz, 5 s. Pairs (i, i + 10) for i = 0..40, but j = 50 (the last index) is dropped as in
  // the script, so i = 0..39: 40 pairs. Estimate moves 1.1 m per second where ground truth moves 1.0.
  const std::vector<double> t = stamps(51, 0.1);
  const RpeResult r =
      evaluate_rpe(sample(t, moving_along_x(1.0)), sample(t, moving_along_x(1.1)), RpeOptions{});
  ASSERT_EQ(r.pairs.size(), 40u);
  for (const auto& pair : r.pairs) {
    EXPECT_NEAR(pair.estimate_stamp_1 - pair.estimate_stamp_0, 1.0, 1e-12);
    EXPECT_NE(pair.estimate_stamp_1, t.back());
  }
  EXPECT_NEAR(r.ground_truth_max_time_difference_s, 0.2, 1e-12);
  EXPECT_NEAR(r.translation_error_m.rmse, 0.1, kTol);
  EXPECT_NEAR(r.translation_error_m.mean, 0.1, kTol);
  EXPECT_NEAR(r.translation_error_m.median, 0.1, kTol);
  EXPECT_NEAR(r.translation_error_m.std, 0.0, kTol);
  EXPECT_NEAR(r.translation_error_m.min, 0.1, kTol);
  EXPECT_NEAR(r.translation_error_m.max, 0.1, kTol);
  EXPECT_NEAR(r.rotation_error_deg.max, 0.0, 1e-6);
}

TEST(Rpe, ExtraYawPerSecondGivesThatAngleInDegrees) {
  // Ground truth turns 0.1 rad/s, the estimate 0.12 rad/s: 0.02 rad per 1 s delta, no translation error.
  const std::vector<double> t = stamps(51, 0.1);
  const RpeResult r = evaluate_rpe(sample(t, turning(0.1)), sample(t, turning(0.12)), RpeOptions{});
  ASSERT_EQ(r.pairs.size(), 40u);
  const double expected_deg = 0.02 * 180.0 / kPi;
  EXPECT_NEAR(r.rotation_error_deg.rmse, expected_deg, kTol);
  EXPECT_NEAR(r.rotation_error_deg.mean, expected_deg, kTol);
  EXPECT_NEAR(r.rotation_error_deg.median, expected_deg, kTol);
  EXPECT_NEAR(r.rotation_error_deg.min, expected_deg, kTol);
  EXPECT_NEAR(r.rotation_error_deg.max, expected_deg, kTol);
  EXPECT_NEAR(r.rotation_error_deg.std, 0.0, kTol);
  EXPECT_NEAR(r.translation_error_m.max, 0.0, kTol);
}

TEST(Rpe, DeltaInFrames) {
  // 20 poses; delta 3 frames: pairs (i, i + 3) with i + 3 < 19 -> i = 0..15: 16 pairs.
  // Over 3 frames (0.3 s) the 0.1 m/s speed difference is 0.03 m.
  const std::vector<double> t = stamps(20, 0.1);
  RpeOptions options;
  options.delta = 3;
  options.delta_unit = DeltaUnit::kFrames;
  const RpeResult r = evaluate_rpe(sample(t, moving_along_x(1.0)), sample(t, moving_along_x(1.1)), options);
  ASSERT_EQ(r.pairs.size(), 16u);
  EXPECT_NEAR(r.translation_error_m.rmse, 0.03, kTol);
  EXPECT_NEAR(r.translation_error_m.max, 0.03, kTol);
  EXPECT_NEAR(r.pairs.back().estimate_stamp_1, t[18], 1e-12);
}

TEST(Rpe, OffsetAndScaleOptions) {
  const std::vector<double> t = stamps(51, 0.1);
  const Trajectory gt = sample(t, moving_along_x(1.0));
  // Estimate stamped 0.5 s late: the offset -0.5 s (added to estimate stamps) realigns them.
  Trajectory late = sample(t, moving_along_x(1.1));
  for (auto& pose : late) pose.timestamp_s += 0.5;
  RpeOptions offset;
  offset.offset_s = -0.5;
  const RpeResult r = evaluate_rpe(gt, late, offset);
  EXPECT_EQ(r.pairs.size(), 40u);
  EXPECT_NEAR(r.translation_error_m.rmse, 0.1, kTol);
  // Estimate at twice the scale: --scale 0.5 removes the error.
  RpeOptions half;
  half.scale = 0.5;
  EXPECT_NEAR(evaluate_rpe(gt, sample(t, moving_along_x(2.0)), half).translation_error_m.max, 0.0, kTol);
}

TEST(Rpe, PairsFarFromGroundTruthStampsAreSkipped) {
  // Delta 10 s. Integer stamps 0..50 for the estimate; ground truth misses 21..29. Median gt interval 1 -> 2
  // s limit. Estimate stamps 23..27 are more than 2 s from any gt stamp (22 and 28 are exactly 2: kept).
  // Pairs (i, i + 10), i = 0..39; skipped when i or i + 10 is in 23..27: i in 13..17 or 23..27 -> 30 pairs.
  std::vector<double> gt_stamps;
  for (int k = 0; k <= 50; ++k) {
    if (k < 21 || k > 29) gt_stamps.push_back(k);
  }
  RpeOptions options;
  options.delta = 10.0;
  const RpeResult r = evaluate_rpe(sample(gt_stamps, moving_along_x(1.0)),
                                   sample(stamps(51, 1.0), moving_along_x(1.0)), options);
  EXPECT_EQ(r.ground_truth_max_time_difference_s, 2.0);
  EXPECT_EQ(r.pairs.size(), 30u);
  for (const auto& pair : r.pairs) {
    EXPECT_FALSE(pair.estimate_stamp_0 >= 23 && pair.estimate_stamp_0 <= 27);
    EXPECT_FALSE(pair.estimate_stamp_1 >= 23 && pair.estimate_stamp_1 <= 27);
  }
  // Pairs using a substituted gt stamp have an error of the stamp mismatch (speed 1 m/s): e.g. est 22 vs
  // gt 20.
  EXPECT_NEAR(r.translation_error_m.max, 2.0, kTol);
  EXPECT_NEAR(r.translation_error_m.min, 0.0, kTol);
}

TEST(Rpe, UnsortedAndDuplicatedInputAsTheScriptsDict) {
  const std::vector<double> t = stamps(51, 0.1);
  const Trajectory gt = sample(t, moving_along_x(1.0));
  Trajectory est = sample(t, moving_along_x(1.1));
  const RpeResult sorted = evaluate_rpe(gt, est, RpeOptions{});
  // An earlier line with the same stamp is replaced by the later (correct) one.
  est.insert(est.begin(), {t[20], SE3(kTilt, Vec3(50.0, 0.0, 0.0))});
  std::mt19937 rng(7);
  std::shuffle(est.begin() + 1, est.end(), rng);
  Trajectory gt_shuffled = gt;
  std::shuffle(gt_shuffled.begin(), gt_shuffled.end(), rng);
  const RpeResult shuffled = evaluate_rpe(gt_shuffled, est, RpeOptions{});
  EXPECT_EQ(shuffled.pairs.size(), sorted.pairs.size());
  EXPECT_NEAR(shuffled.translation_error_m.max, 0.1, kTol);
  EXPECT_NEAR(shuffled.translation_error_m.rmse, sorted.translation_error_m.rmse, 1e-12);
  // The wrong pose as the last line wins and shows up.
  Trajectory wrong_last = sample(t, moving_along_x(1.1));
  wrong_last.push_back({t[20], SE3(kTilt, Vec3(50.0, 0.0, 0.0))});
  EXPECT_GT(evaluate_rpe(gt, wrong_last, RpeOptions{}).translation_error_m.max, 40.0);
}

TEST(Rpe, NoOverlapOrNoPairsIsClearError) {
  const Trajectory gt = sample(stamps(51, 0.1), moving_along_x(1.0));
  const Trajectory far = sample(stamps(51, 0.1, 1000.0), moving_along_x(1.0));
  expect_error_message([&] { evaluate_rpe(gt, far, RpeOptions{}, "gt.txt", "est.txt"); },
                       {"overlapping timestamps", "too small", "gt.txt", "est.txt"});
  RpeOptions long_delta;
  long_delta.delta = 100.0;  // every j is the last index -> no pairs
  expect_error_message([&] { evaluate_rpe(gt, gt, long_delta, "gt.txt", "est.txt"); },
                       {"couldn't find matching timestamp pairs", "gt.txt", "est.txt", "0 pair(s)"});
  expect_error_message([&] { evaluate_rpe(gt, Trajectory{}, RpeOptions{}, "gt.txt", "est.txt"); },
                       {"est.txt", "no poses"});
}

TEST(Rpe, OptionsCheckNamesBadValue) {
  RpeOptions options;
  options.delta = 0.0;
  expect_error_message([&] { options.check(); }, {"--delta", "0"});
  expect_error_message([] { eval::parse_delta_unit("m"); }, {"'m'"});
  EXPECT_EQ(eval::parse_delta_unit("frames"), DeltaUnit::kFrames);
  EXPECT_EQ(eval::parse_delta_unit("f"), DeltaUnit::kFrames);
}
