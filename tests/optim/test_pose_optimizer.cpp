#include <gtest/gtest.h>
#include <ceres/ceres.h>

#include <cmath>
#include <random>

#include "crowdslam/optim/pose_optimizer.h"
#include "crowdslam/util/error.h"
#include "synthetic.h"

using namespace crowdslam::optim;
using namespace crowdslam::optim::test;

namespace {

struct OutlierStats {
  int outliers = 0;
  int outliers_flagged = 0;
  int inliers = 0;
  int inliers_kept = 0;
};

OutlierStats count(const PoseScene& scene, const PoseOptimizationResult& result) {
  OutlierStats s;
  for (std::size_t i = 0; i < scene.is_outlier.size(); ++i) {
    if (scene.is_outlier[i]) {
      ++s.outliers;
      s.outliers_flagged += result.inliers[i] ? 0 : 1;
    } else {
      ++s.inliers;
      s.inliers_kept += result.inliers[i] ? 1 : 0;
    }
  }
  return s;
}

// Ceres reference: plain least squares with auto-diff, quaternion manifold.
template <bool kStereo>
struct ReprojectionFunctor {
  PinholeCamera camera;
  PoseObservation obs;
  template <typename T>
  bool operator()(const T* q, const T* t, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> rotation(q);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> translation(t);
    const Eigen::Matrix<T, 3, 1> p = rotation * obs.point_world.cast<T>() + translation;
    const T u = camera.fx * p.x() / p.z() + camera.cx;
    const T v = camera.fy * p.y() / p.z() + camera.cy;
    const double w = std::sqrt(obs.inv_sigma2);
    residual[0] = w * (u - obs.pixel.x());
    residual[1] = w * (v - obs.pixel.y());
    if constexpr (kStereo) residual[2] = w * (u - camera.bf / p.z() - obs.right_u);
    return true;
  }
};

SE3 solve_with_ceres(const PinholeCamera& camera, const SE3& initial, const std::vector<PoseObservation>& observations) {
  Eigen::Quaterniond q = initial.rotation();
  Vec3 t = initial.translation();
  ceres::Problem problem;
  for (const PoseObservation& obs : observations) {
    if (obs.is_stereo()) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ReprojectionFunctor<true>, 3, 4, 3>(
                                   new ReprojectionFunctor<true>{camera, obs}),
                               nullptr, q.coeffs().data(), t.data());
    } else {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ReprojectionFunctor<false>, 2, 4, 3>(
                                   new ReprojectionFunctor<false>{camera, obs}),
                               nullptr, q.coeffs().data(), t.data());
    }
  }
  problem.SetManifold(q.coeffs().data(), new ceres::EigenQuaternionManifold);
  ceres::Solver::Options options;
  options.max_num_iterations = 100;
  options.function_tolerance = 1e-16;
  options.gradient_tolerance = 1e-16;
  options.parameter_tolerance = 1e-16;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  return SE3(q, t);
}

}  // namespace

TEST(PoseOptimizer, RecoversPoseWithNoiseAndOutliers) {
  const PinholeCamera camera = test_camera();
  PoseSceneSpec spec;
  spec.outlier_ratio = 0.2;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    spec.seed = seed;
    const PoseScene scene = make_pose_scene(camera, spec);
    std::mt19937 rng(100 + seed);
    const SE3 initial = perturb(scene.truth, 0.05, 3.0 * M_PI / 180.0, rng);
    const PoseOptimizationResult result = optimize_pose(camera, initial, scene.observations);
    ASSERT_TRUE(result.success);
    EXPECT_LT(translation_error(result.cam_from_world, scene.truth), 0.01) << "seed " << seed;
    EXPECT_LT(rotation_error_rad(result.cam_from_world, scene.truth), 0.2 * M_PI / 180.0) << "seed " << seed;
    const OutlierStats s = count(scene, result);
    ASSERT_GT(s.outliers, 30);
    EXPECT_GE(s.outliers_flagged, 0.95 * s.outliers) << "seed " << seed;
    // chi2 test at 95%: about 5% of true inliers are rejected.
    EXPECT_GE(s.inliers_kept, 0.88 * s.inliers) << "seed " << seed;
    int flags = 0;
    for (bool f : result.inliers) flags += f ? 1 : 0;
    EXPECT_EQ(flags, result.num_inliers);
  }
}

TEST(PoseOptimizer, MixedMonoStereoWithOutliers) {
  const PinholeCamera camera = test_camera();
  PoseSceneSpec spec;
  spec.outlier_ratio = 0.2;
  spec.stereo_ratio = 0.5;
  spec.seed = 11;
  PoseScene scene = make_pose_scene(camera, spec);
  // Stereo observations whose only error is a wrong right coordinate (bad depth) are outliers too.
  int depth_outliers = 0;
  for (std::size_t i = 0; i < scene.observations.size() && depth_outliers < 10; ++i) {
    if (scene.observations[i].is_stereo() && !scene.is_outlier[i]) {
      scene.observations[i].right_u -= 25.0;
      scene.is_outlier[i] = true;
      ++depth_outliers;
    }
  }
  ASSERT_EQ(depth_outliers, 10);
  std::mt19937 rng(5);
  const SE3 initial = perturb(scene.truth, 0.05, 3.0 * M_PI / 180.0, rng);
  const PoseOptimizationResult result = optimize_pose(camera, initial, scene.observations);
  ASSERT_TRUE(result.success);
  EXPECT_LT(translation_error(result.cam_from_world, scene.truth), 0.01);
  EXPECT_LT(rotation_error_rad(result.cam_from_world, scene.truth), 0.2 * M_PI / 180.0);
  const OutlierStats s = count(scene, result);
  EXPECT_GE(s.outliers_flagged, 0.95 * s.outliers);
  EXPECT_GE(s.inliers_kept, 0.88 * s.inliers);
}

TEST(PoseOptimizer, StereoOnlyFixesScaleOfTranslation) {
  // Stereo observations constrain depth: a pure forward offset of 10 cm is recovered.
  const PinholeCamera camera = test_camera();
  PoseSceneSpec spec;
  spec.stereo_ratio = 1.0;
  spec.num_points = 100;
  spec.seed = 4;
  const PoseScene scene = make_pose_scene(camera, spec);
  const SE3 initial(scene.truth.rotation(), scene.truth.translation() + Vec3(0, 0, 0.1));
  const PoseOptimizationResult result = optimize_pose(camera, initial, scene.observations);
  ASSERT_TRUE(result.success);
  EXPECT_LT(translation_error(result.cam_from_world, scene.truth), 0.01);
}

TEST(PoseOptimizer, MatchesCeresWithoutOutliers) {
  const PinholeCamera camera = test_camera();
  PoseSceneSpec spec;
  spec.pixel_noise = 0.5;  // small enough that no observation exceeds the chi2 thresholds
  spec.stereo_ratio = 0.4;
  spec.seed = 21;
  const PoseScene scene = make_pose_scene(camera, spec);
  std::mt19937 rng(8);
  const SE3 initial = perturb(scene.truth, 0.05, 3.0 * M_PI / 180.0, rng);
  const PoseOptimizationResult result = optimize_pose(camera, initial, scene.observations);
  ASSERT_TRUE(result.success);
  ASSERT_EQ(result.num_inliers, static_cast<int>(scene.observations.size()));
  const SE3 reference = solve_with_ceres(camera, initial, scene.observations);
  EXPECT_LT((result.cam_from_world.translation() - reference.translation()).norm(), 1e-6);
  EXPECT_LT(rotation_error_rad(result.cam_from_world, reference), 1e-6);
  // And both are near the truth, so the comparison is not between two wrong answers.
  EXPECT_LT(translation_error(reference, scene.truth), 0.01);
}

TEST(PoseOptimizer, TooFewObservationsFails) {
  const PinholeCamera camera = test_camera();
  PoseSceneSpec spec;
  spec.num_points = 2;
  const PoseScene scene = make_pose_scene(camera, spec);
  const SE3 initial = SE3::exp((Vec6() << 0.1, 0.2, 0.3, 0.01, 0.02, 0.03).finished());
  const PoseOptimizationResult result = optimize_pose(camera, initial, scene.observations);
  EXPECT_FALSE(result.success);
  EXPECT_EQ(result.num_inliers, 0);
  ASSERT_EQ(result.inliers.size(), 2u);
  EXPECT_LT((result.cam_from_world.translation() - initial.translation()).norm(), 1e-15);

  const PoseOptimizationResult empty = optimize_pose(camera, initial, {});
  EXPECT_FALSE(empty.success);
  EXPECT_TRUE(empty.inliers.empty());
}

TEST(PoseOptimizer, PointsBehindCameraAreOutliers) {
  const PinholeCamera camera = test_camera();
  PoseSceneSpec spec;
  spec.num_points = 50;
  spec.seed = 9;
  PoseScene scene = make_pose_scene(camera, spec);
  // Mirror three points through the camera centre: behind the camera, same pixel.
  const SE3 world_from_cam = scene.truth.inverse();
  for (int i = 0; i < 3; ++i) {
    const Vec3 p_cam = scene.truth * scene.observations[i].point_world;
    scene.observations[i].point_world = world_from_cam * (-p_cam);
  }
  const PoseOptimizationResult result = optimize_pose(camera, scene.truth, scene.observations);
  ASSERT_TRUE(result.success);
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(result.inliers[i]) << i;
  EXPECT_LT(translation_error(result.cam_from_world, scene.truth), 0.02);
}

TEST(PoseOptimizer, OptionsCheckNamesBadValue) {
  PoseOptimizerOptions options;
  EXPECT_NO_THROW(options.check());
  options.rounds = 0;
  try {
    options.check();
    FAIL() << "expected InputError";
  } catch (const crowdslam::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("rounds"), std::string::npos) << e.what();
  }
  options = PoseOptimizerOptions{};
  options.chi2_mono = -1.0;
  EXPECT_THROW(options.check(), crowdslam::InputError);
}
