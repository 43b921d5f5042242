// Relative poses between keyframes in local bundle adjustment (BaRelativePose, SchurRelativePose): the
// residual's Jacobians, a keyframe placed by a relative pose alone, both solvers agreeing, and a keyframe
// that its observations place poorly held by its measured relative pose.
#include <gtest/gtest.h>

#include <random>

#include "crowdslam/optim/bundle_adjustment.h"
#include "crowdslam/optim/se3_update.h"
#include "synthetic.h"

using namespace crowdslam::optim;
using namespace crowdslam::optim::test;

namespace {

SE3 random_pose(std::mt19937& rng, double translation, double angle) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Vec3 axis = Vec3(n(rng), n(rng), n(rng)).normalized();
  return SE3(Eigen::AngleAxisd(angle, axis).toRotationMatrix(), translation * Vec3(n(rng), n(rng), n(rng)));
}

const BaKeyframe& keyframe_of(const std::vector<BaKeyframe>& keyframes, int id) {
  return *std::find_if(keyframes.begin(), keyframes.end(), [&](const BaKeyframe& k) { return k.id == id; });
}

}  // namespace

TEST(RelativePoseError, JacobiansMatchFiniteDifferencesOfTheLeftUpdate) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 5; ++trial) {
    const SE3 a = random_pose(rng, 1.0, 0.8);
    const SE3 b = random_pose(rng, 1.0, 0.8);
    // At zero error the Jacobians are exact; a measurement 1e-4 off keeps them within its second order.
    const SE3 measured = SE3::exp((Vec6() << 1e-4, -1e-4, 2e-4, 1e-4, 0, -1e-4).finished()) * a * b.inverse();
    Eigen::Matrix<double, 6, 6> j_b;
    const Vec6 e0 = relative_pose_error(a, b, measured, &j_b);
    const double h = 1e-6;
    for (int k = 0; k < 6; ++k) {
      Vec6 delta = Vec6::Zero();
      delta(k) = h;
      const Vec6 d_a = (relative_pose_error(left_update(delta, a), b, measured) - e0) / h;
      const Vec6 d_b = (relative_pose_error(a, left_update(delta, b), measured) - e0) / h;
      EXPECT_LT((d_a - Vec6::Unit(k)).norm(), 1e-3) << "pose a, column " << k;
      EXPECT_LT((d_b - j_b.col(k)).norm(), 1e-3) << "pose b, column " << k;
    }
  }
}

TEST(BundleAdjustment, AKeyframeWithOnlyARelativePoseLandsWhereItSays) {
  const PinholeCamera camera = test_camera();
  BaSceneSpec spec;
  spec.num_keyframes = 4;
  spec.num_points = 120;
  spec.num_outliers = 0;
  const BaScene scene = make_ba_scene(camera, spec);
  std::vector<BaKeyframe> keyframes = scene.keyframes;
  const SE3 fixed_pose = keyframe_of(keyframes, 100).cam_from_world;  // num_fixed = 2: ids 100, 101
  const SE3 measured = SE3::exp((Vec6() << 0.1, -0.02, 0.05, 0.01, 0.03, -0.02).finished());
  keyframes.push_back({999, SE3(), false});  // no observations: placed by the relative pose alone
  BaRelativePose edge;
  edge.keyframe_id = 999;
  edge.other_id = 100;
  edge.cam_from_other = measured;
  edge.translation_sigma = 0.01;
  edge.rotation_sigma_rad = 0.002;
  for (const BaLinearSolver solver : {BaLinearSolver::kOwnSchur, BaLinearSolver::kDenseSchur}) {
    BundleAdjustmentOptions options;
    options.linear_solver = solver;
    const auto result =
        local_bundle_adjustment(camera, keyframes, scene.points, scene.observations, options, nullptr, {}, {edge});
    const SE3 expected = measured * fixed_pose;
    const SE3 got = keyframe_of(result.keyframes, 999).cam_from_world;
    EXPECT_LT(translation_error(got, expected), 1e-6) << static_cast<int>(solver);
    EXPECT_LT(rotation_error_rad(got, expected), 1e-6) << static_cast<int>(solver);
  }
  // An edge between two fixed keyframes, or to an unknown keyframe, changes nothing.
  BaRelativePose idle = edge;
  idle.keyframe_id = 101;
  BaRelativePose unknown = edge;
  unknown.other_id = 12345;
  const auto plain = local_bundle_adjustment(camera, scene.keyframes, scene.points, scene.observations);
  const auto with_idle = local_bundle_adjustment(camera, scene.keyframes, scene.points, scene.observations, {},
                                                 nullptr, {}, {idle, unknown});
  for (std::size_t k = 0; k < plain.keyframes.size(); ++k) {
    EXPECT_EQ(plain.keyframes[k].cam_from_world.translation(), with_idle.keyframes[k].cam_from_world.translation());
  }
}

TEST(BundleAdjustment, ARelativePoseHoldsAKeyframeItsFewObservationsPlacePoorly) {
  const PinholeCamera camera = test_camera();
  BaSceneSpec spec;
  spec.num_keyframes = 4;
  spec.num_points = 200;
  spec.num_outliers = 0;
  spec.stereo_ratio = 0.0;
  const BaScene scene = make_ba_scene(camera, spec);
  // The last keyframe keeps only 8 of its observations, with 4 px of extra noise: its pose is loose.
  const int weak = scene.keyframes.back().id;
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 4.0);
  std::vector<BaObservation> observations;
  int kept = 0;
  for (BaObservation obs : scene.observations) {
    if (obs.keyframe_id == weak) {
      if (kept++ >= 8) continue;
      obs.pixel += Vec2(noise(rng), noise(rng));
    }
    observations.push_back(obs);
  }
  const SE3 truth_weak = keyframe_of(scene.truth_keyframes, weak).cam_from_world;
  const SE3 truth_before = keyframe_of(scene.truth_keyframes, weak - 1).cam_from_world;
  BaRelativePose edge;
  edge.keyframe_id = weak;
  edge.other_id = weak - 1;
  edge.cam_from_other = truth_weak * truth_before.inverse();
  edge.translation_sigma = 0.005;
  edge.rotation_sigma_rad = 0.1 * M_PI / 180.0;
  const auto without = local_bundle_adjustment(camera, scene.keyframes, scene.points, observations);
  BundleAdjustmentOptions own;
  own.linear_solver = BaLinearSolver::kOwnSchur;
  BundleAdjustmentOptions ceres_dense;
  ceres_dense.linear_solver = BaLinearSolver::kDenseSchur;
  const auto with = local_bundle_adjustment(camera, scene.keyframes, scene.points, observations, own, nullptr, {}, {edge});
  const auto with_ceres =
      local_bundle_adjustment(camera, scene.keyframes, scene.points, observations, ceres_dense, nullptr, {}, {edge});
  const double error_without = rotation_error_rad(keyframe_of(without.keyframes, weak).cam_from_world, truth_weak);
  const double error_with = rotation_error_rad(keyframe_of(with.keyframes, weak).cam_from_world, truth_weak);
  EXPECT_GT(error_without, 0.2 * M_PI / 180.0);
  EXPECT_LT(error_with, 0.3 * error_without);
  // Both solvers reach the same minimum with the relative pose in the problem (each stops at a relative
  // cost change of 1e-6: agreement well under a millimetre, as without relative poses).
  EXPECT_NEAR(with.final_cost, with_ceres.final_cost, 1e-4 * with_ceres.final_cost);
  for (std::size_t k = 0; k < with.keyframes.size(); ++k) {
    EXPECT_LT(translation_error(with.keyframes[k].cam_from_world, with_ceres.keyframes[k].cam_from_world), 2e-4);
    EXPECT_LT(rotation_error_rad(with.keyframes[k].cam_from_world, with_ceres.keyframes[k].cam_from_world), 5e-5);
  }
}
