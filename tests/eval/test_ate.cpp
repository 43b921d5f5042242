#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>

#include "crowdslam/eval/ate.h"
#include "crowdslam/util/error.h"

using namespace crowdslam;
using crowdslam::eval::Alignment;
using crowdslam::eval::AteOptions;
using crowdslam::eval::AteResult;
using crowdslam::eval::evaluate_ate;
using crowdslam::geometry::Mat3;
using crowdslam::geometry::SE3;
using crowdslam::geometry::Vec3;
using crowdslam::io::Trajectory;

namespace {

constexpr double kTol = 1e-9;

// Corners of a box with distinct half-sizes 1, 2, 3: a full-rank point set, centred at the origin.
std::vector<Vec3> box_corners() {
  std::vector<Vec3> corners;
  for (int sx : {-1, 1})
    for (int sy : {-1, 1})
      for (int sz : {-1, 1}) corners.emplace_back(1.0 * sx, 2.0 * sy, 3.0 * sz);
  return corners;
}

// Poses at stamps 0, 1, 2, ... with the given positions and a rotation varying along the trajectory.
Trajectory make_trajectory(const std::vector<Vec3>& positions, double first_stamp = 0.0) {
  Trajectory trajectory;
  for (std::size_t k = 0; k < positions.size(); ++k) {
    const Eigen::Quaterniond q(Eigen::AngleAxisd(0.1 * k, Vec3(0.2, -1.0, 0.5).normalized()));
    trajectory.push_back({first_stamp + static_cast<double>(k), SE3(q, positions[k])});
  }
  return trajectory;
}

// A scattered, non-planar ground-truth path of 12 points.
std::vector<Vec3> scattered_points() {
  std::vector<Vec3> points = box_corners();
  points.emplace_back(0.5, -0.25, 4.0);
  points.emplace_back(-2.0, 1.5, 0.5);
  points.emplace_back(3.0, 0.0, -1.0);
  points.emplace_back(0.0, -3.5, 2.0);
  return points;
}

Mat3 test_rotation() { return Eigen::AngleAxisd(0.7, Vec3(1.0, -2.0, 0.5).normalized()).toRotationMatrix(); }

// Ground truth = 16 poses at the 8 box corners, each corner twice; the estimate is displaced along x
// by +a_k at the first visit of corner k and by -a_k at the second. The displacements sum to zero and
// are uncorrelated with the positions, so the cross-covariance is the (symmetric, positive definite)
// scatter matrix of the corners and the optimal alignment is exactly the identity: errors are a_k.
void paired_offsets(const std::vector<double>& a, Trajectory& gt, Trajectory& est) {
  const std::vector<Vec3> corners = box_corners();
  std::vector<Vec3> gt_points;
  std::vector<Vec3> est_points;
  for (int visit : {1, -1}) {
    for (std::size_t k = 0; k < corners.size(); ++k) {
      gt_points.push_back(corners[k]);
      est_points.push_back(corners[k] + visit * a[k] * Vec3::UnitX());
    }
  }
  gt = make_trajectory(gt_points);
  est = make_trajectory(est_points);
}

AteOptions with_alignment(Alignment alignment) {
  AteOptions options;
  options.alignment = alignment;
  return options;
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

TEST(Ate, IdenticalTrajectoriesGiveZeroErrorAndIdentityAlignment) {
  const Trajectory gt = make_trajectory(scattered_points());
  for (Alignment alignment : {Alignment::kSe3, Alignment::kSim3, Alignment::kNone}) {
    const AteResult r = evaluate_ate(gt, gt, with_alignment(alignment));
    EXPECT_EQ(r.translation_error_m.count, gt.size());
    EXPECT_EQ(r.matches.size(), gt.size());
    EXPECT_NEAR(r.translation_error_m.rmse, 0.0, kTol);
    EXPECT_NEAR(r.translation_error_m.max, 0.0, kTol);
    EXPECT_NEAR((r.alignment.rotation - Mat3::Identity()).norm(), 0.0, kTol);
    EXPECT_NEAR(r.alignment.translation.norm(), 0.0, kTol);
    EXPECT_NEAR(r.alignment.scale, 1.0, kTol);
  }
}

TEST(Ate, RigidlyMovedEstimateIsZeroAfterSe3AndAlignmentIsRecovered) {
  const std::vector<Vec3> gt_points = scattered_points();
  const Mat3 rotation = test_rotation();
  const Vec3 translation(1.5, -0.75, 2.0);
  std::vector<Vec3> est_points;  // gt = rotation * est + translation
  for (const Vec3& p : gt_points) est_points.push_back(rotation.transpose() * (p - translation));
  const AteResult r = evaluate_ate(make_trajectory(gt_points), make_trajectory(est_points), AteOptions{});
  EXPECT_EQ(r.translation_error_m.count, gt_points.size());
  EXPECT_NEAR(r.translation_error_m.rmse, 0.0, kTol);
  EXPECT_NEAR(r.translation_error_m.max, 0.0, kTol);
  EXPECT_NEAR((r.alignment.rotation - rotation).norm(), 0.0, kTol);
  EXPECT_NEAR((r.alignment.translation - translation).norm(), 0.0, kTol);
  EXPECT_EQ(r.alignment.scale, 1.0);
}

TEST(Ate, TranslatedEstimateWithoutAlignmentHasTheShiftAsError) {
  const std::vector<Vec3> gt_points = scattered_points();
  std::vector<Vec3> est_points;
  for (const Vec3& p : gt_points) est_points.push_back(p - Vec3(1.0, 2.0, 2.0));  // |(1, 2, 2)| = 3
  const Trajectory gt = make_trajectory(gt_points);
  const Trajectory est = make_trajectory(est_points);
  const AteResult none = evaluate_ate(gt, est, with_alignment(Alignment::kNone));
  EXPECT_NEAR(none.translation_error_m.rmse, 3.0, kTol);
  EXPECT_NEAR(none.translation_error_m.mean, 3.0, kTol);
  EXPECT_NEAR(none.translation_error_m.median, 3.0, kTol);
  EXPECT_NEAR(none.translation_error_m.std, 0.0, kTol);
  EXPECT_NEAR(none.translation_error_m.min, 3.0, kTol);
  EXPECT_NEAR(none.translation_error_m.max, 3.0, kTol);
  EXPECT_NEAR(evaluate_ate(gt, est, AteOptions{}).translation_error_m.rmse, 0.0, kTol);
}

TEST(Ate, AlternatingOffsetsGiveRmseEqualToOffset) {
  const double d = 0.05;
  Trajectory gt;
  Trajectory est;
  paired_offsets(std::vector<double>(8, d), gt, est);
  for (Alignment alignment : {Alignment::kSe3, Alignment::kNone}) {
    const AteResult r = evaluate_ate(gt, est, with_alignment(alignment));
    EXPECT_EQ(r.translation_error_m.count, 16u);
    EXPECT_NEAR(r.translation_error_m.rmse, d, kTol);
    EXPECT_NEAR(r.translation_error_m.mean, d, kTol);
    EXPECT_NEAR(r.translation_error_m.std, 0.0, kTol);
    EXPECT_NEAR((r.alignment.rotation - Mat3::Identity()).norm(), 0.0, kTol);
  }
}

TEST(Ate, KnownNoiseGivesHandComputedStatistics) {
  // Offsets a_k = {1, 1, 2, 3, 5, 8, 13, 21} cm, each occurring twice (16 errors).
  const std::vector<double> a{0.01, 0.01, 0.02, 0.03, 0.05, 0.08, 0.13, 0.21};
  Trajectory gt;
  Trajectory est;
  paired_offsets(a, gt, est);
  const AteResult r = evaluate_ate(gt, est, AteOptions{});
  // sum = 2 * 54 cm = 1.08 m; sum of squares = 2 * 714 cm^2 = 0.1428 m^2; N = 16.
  const double mean = 1.08 / 16;
  const double mean_square = 0.1428 / 16;
  EXPECT_EQ(r.translation_error_m.count, 16u);
  EXPECT_NEAR(r.translation_error_m.rmse, std::sqrt(mean_square), kTol);
  EXPECT_NEAR(r.translation_error_m.mean, mean, kTol);
  // Sorted: 1 1 1 1 2 2 3 3 | 5 5 8 8 13 13 21 21 -> median (3 + 5) / 2 cm.
  EXPECT_NEAR(r.translation_error_m.median, 0.04, kTol);
  EXPECT_NEAR(r.translation_error_m.std, std::sqrt(mean_square - mean * mean), kTol);
  EXPECT_NEAR(r.translation_error_m.min, 0.01, kTol);
  EXPECT_NEAR(r.translation_error_m.max, 0.21, kTol);
}

TEST(Ate, Sim3RecoversKnownScale) {
  const std::vector<Vec3> gt_points = scattered_points();
  const Mat3 rotation = test_rotation();
  const Vec3 translation(-0.5, 4.0, 1.0);
  const double scale = 2.5;
  std::vector<Vec3> est_points;  // gt = scale * rotation * est + translation
  for (const Vec3& p : gt_points) est_points.push_back(rotation.transpose() * (p - translation) / scale);
  const Trajectory gt = make_trajectory(gt_points);
  const Trajectory est = make_trajectory(est_points);

  const AteResult sim3 = evaluate_ate(gt, est, with_alignment(Alignment::kSim3));
  EXPECT_NEAR(sim3.translation_error_m.rmse, 0.0, kTol);
  EXPECT_NEAR(sim3.alignment.scale, scale, kTol);
  EXPECT_NEAR((sim3.alignment.rotation - rotation).norm(), 0.0, kTol);
  EXPECT_NEAR((sim3.alignment.translation - translation).norm(), 0.0, kTol);
  // SE3 cannot absorb the scale.
  EXPECT_GT(evaluate_ate(gt, est, AteOptions{}).translation_error_m.rmse, 0.5);
  // A fixed --scale of 2.5 makes SE3 exact again.
  AteOptions fixed_scale;
  fixed_scale.scale = scale;
  EXPECT_NEAR(evaluate_ate(gt, est, fixed_scale).translation_error_m.rmse, 0.0, kTol);
}

TEST(Ate, UnsortedInputGivesSameResultAsSorted) {
  const std::vector<double> a{0.01, 0.01, 0.02, 0.03, 0.05, 0.08, 0.13, 0.21};
  Trajectory gt;
  Trajectory est;
  paired_offsets(a, gt, est);
  const AteResult sorted = evaluate_ate(gt, est, AteOptions{});
  std::mt19937 rng(42);
  std::shuffle(gt.begin(), gt.end(), rng);
  std::shuffle(est.begin(), est.end(), rng);
  const AteResult shuffled = evaluate_ate(gt, est, AteOptions{});
  EXPECT_NEAR(shuffled.translation_error_m.rmse, sorted.translation_error_m.rmse, 1e-12);
  EXPECT_NEAR(shuffled.translation_error_m.median, sorted.translation_error_m.median, 1e-12);
  EXPECT_NEAR(shuffled.translation_error_m.std, sorted.translation_error_m.std, 1e-12);
  EXPECT_EQ(shuffled.errors_m.size(), 16u);
}

TEST(Ate, DuplicateStampsLastLineWins) {
  const std::vector<Vec3> points = scattered_points();
  const Trajectory gt = make_trajectory(points);
  Trajectory est = gt;
  const io::StampedPose wrong{est[5].timestamp_s,
                              SE3(est[5].world_from_cam.rotation(), points[5] + Vec3(100, 0, 0))};
  Trajectory wrong_first = est;
  wrong_first.insert(wrong_first.begin() + 2, wrong);  // earlier line, replaced by the later one
  const AteResult r1 = evaluate_ate(gt, wrong_first, with_alignment(Alignment::kNone));
  EXPECT_EQ(r1.estimate_poses, points.size());
  EXPECT_NEAR(r1.translation_error_m.max, 0.0, kTol);
  Trajectory wrong_last = est;
  wrong_last.push_back(wrong);
  const AteResult r2 = evaluate_ate(gt, wrong_last, with_alignment(Alignment::kNone));
  EXPECT_EQ(r2.estimate_poses, points.size());
  EXPECT_NEAR(r2.translation_error_m.max, 100.0, kTol);
  EXPECT_NEAR(r2.translation_error_m.mean, 100.0 / points.size(), kTol);
}

TEST(Ate, AssociationWindowAndOffset) {
  const std::vector<Vec3> points = scattered_points();
  const Trajectory gt = make_trajectory(points);
  // 15 ms late: matched with the default 20 ms window.
  EXPECT_EQ(evaluate_ate(gt, make_trajectory(points, 0.015), AteOptions{}).matches.size(), points.size());
  // 25 ms late: nothing within 20 ms, but within 30 ms.
  const Trajectory late = make_trajectory(points, 0.025);
  expect_error_message([&] { evaluate_ate(gt, late, AteOptions{}, "gt.txt", "est.txt"); },
                       {"no overlapping timestamps", "gt.txt", "est.txt", "0.02 s"});
  AteOptions wide;
  wide.max_difference_s = 0.03;
  EXPECT_EQ(evaluate_ate(gt, late, wide).matches.size(), points.size());
  // 100 s later: only an offset of -100 s brings them together (offset is added to the estimate).
  const Trajectory shifted = make_trajectory(points, 100.0);
  AteOptions offset;
  offset.offset_s = -100.0;
  const AteResult r = evaluate_ate(gt, shifted, offset);
  EXPECT_EQ(r.matches.size(), points.size());
  EXPECT_NEAR(r.translation_error_m.rmse, 0.0, kTol);
}

TEST(Ate, TooFewMatchesOrEmptyInputIsClearError) {
  const std::vector<Vec3> points = scattered_points();
  const Trajectory gt = make_trajectory(points);
  // Estimate overlaps the last two ground-truth stamps only.
  const Trajectory two = make_trajectory(points, static_cast<double>(points.size() - 2));
  expect_error_message([&] { evaluate_ate(gt, two, AteOptions{}, "gt.txt", "est.txt"); },
                       {"only 2 pose(s)", "gt.txt", "est.txt", "at least 3"});
  expect_error_message([&] { evaluate_ate(gt, Trajectory{}, AteOptions{}, "gt.txt", "est.txt"); },
                       {"est.txt", "no poses"});
  expect_error_message([&] { evaluate_ate(Trajectory{}, gt, AteOptions{}, "gt.txt", "est.txt"); },
                       {"gt.txt", "no poses"});
}

TEST(Ate, OptionsCheckNamesBadValue) {
  AteOptions options;
  options.max_difference_s = 0.0;
  expect_error_message([&] { options.check(); }, {"--max-diff", "0"});
  options = AteOptions{};
  options.scale = -1.0;
  expect_error_message([&] { options.check(); }, {"--scale", "-1"});
  expect_error_message([] { eval::parse_alignment("se4"); }, {"'se4'"});
  EXPECT_EQ(eval::parse_alignment("sim3"), Alignment::kSim3);
}

TEST(Ate, ApplyAlignmentMapsEstimatePosesOntoGroundTruth) {
  const std::vector<Vec3> gt_points = scattered_points();
  const Trajectory gt = make_trajectory(gt_points);
  const Mat3 rotation = test_rotation();
  const Vec3 translation(1.5, -0.75, 2.0);
  const SE3 gt_from_est(rotation, translation);
  Trajectory est;
  for (const auto& pose : gt) est.push_back({pose.timestamp_s, gt_from_est.inverse() * pose.world_from_cam});
  const AteResult r = evaluate_ate(gt, est, AteOptions{});
  const Trajectory aligned = eval::apply_alignment(est, r.alignment, 1.0);
  ASSERT_EQ(aligned.size(), gt.size());
  for (std::size_t k = 0; k < gt.size(); ++k) {
    EXPECT_NEAR((aligned[k].world_from_cam.translation() - gt[k].world_from_cam.translation()).norm(), 0.0,
                kTol);
    EXPECT_NEAR(aligned[k].world_from_cam.rotation().angularDistance(gt[k].world_from_cam.rotation()), 0.0,
                kTol);
  }
}
