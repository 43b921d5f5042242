#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "crowdslam/optim/ceres_pose.h"
#include "crowdslam/optim/se3_update.h"
#include "synthetic.h"

using namespace crowdslam::optim;
using namespace crowdslam::optim::test;

namespace {

// Tangent-space Jacobians: analytic (ambient Jacobian times Se3Manifold::PlusJacobian) against
// central differences of residual(Plus(pose, delta), point + d). ceres::GradientChecker does not
// apply here: it differentiates in the ambient quaternion space, which these costs do not model.
template <int kResiduals>
double max_jacobian_error(const ceres::CostFunction& cost, const PoseBlock& pose, const Vec3& point) {
  using Ambient = Eigen::Matrix<double, kResiduals, 7, Eigen::RowMajor>;
  using Tangent = Eigen::Matrix<double, kResiduals, 6>;
  using PointJ = Eigen::Matrix<double, kResiduals, 3, Eigen::RowMajor>;
  using Residual = Eigen::Matrix<double, kResiduals, 1>;
  Se3Manifold manifold;
  Ambient j_pose;
  PointJ j_point;
  Residual r;
  const double* parameters[] = {pose.data(), point.data()};
  double* jacobians[] = {j_pose.data(), j_point.data()};
  EXPECT_TRUE(cost.Evaluate(parameters, r.data(), jacobians));
  Eigen::Matrix<double, 7, 6, Eigen::RowMajor> plus_jacobian;
  manifold.PlusJacobian(pose.data(), plus_jacobian.data());
  const Tangent analytic_pose = j_pose * plus_jacobian;

  auto residual_at = [&](const Vec6& delta, const Vec3& d_point) {
    PoseBlock moved;
    manifold.Plus(pose.data(), delta.data(), moved.data());
    const Vec3 p = point + d_point;
    const double* params[] = {moved.data(), p.data()};
    Residual out;
    cost.Evaluate(params, out.data(), nullptr);
    return out;
  };
  const double h = 1e-6;
  double worst = 0.0;
  for (int i = 0; i < 6; ++i) {
    Vec6 d = Vec6::Zero();
    d(i) = h;
    const Residual numeric = (residual_at(d, Vec3::Zero()) - residual_at(-d, Vec3::Zero())) / (2 * h);
    worst = std::max(worst, (numeric - analytic_pose.col(i)).norm() / std::max(1.0, numeric.norm()));
  }
  for (int i = 0; i < 3; ++i) {
    Vec3 d = Vec3::Zero();
    d(i) = h;
    const Residual numeric = (residual_at(Vec6::Zero(), d) - residual_at(Vec6::Zero(), -d)) / (2 * h);
    worst = std::max(worst, (numeric - j_point.col(i)).norm() / std::max(1.0, numeric.norm()));
  }
  return worst;
}

}  // namespace

TEST(CeresPose, MonoCostJacobiansMatchNumeric) {
  std::mt19937 rng(2);
  const PinholeCamera camera = test_camera();
  for (int trial = 0; trial < 5; ++trial) {
    const SE3 pose = random_pose(rng);
    const Vec3 point = random_visible_point(camera, pose, 1.0, 6.0, rng);
    const MonoReprojectionCost cost(CostCamera::from(camera), camera.project(pose * point) + Vec2(1.5, -2.0), 1.44);
    EXPECT_LT(max_jacobian_error<2>(cost, to_pose_block(pose), point), 1e-6);
  }
}

TEST(CeresPose, StereoCostJacobiansMatchNumeric) {
  std::mt19937 rng(3);
  const PinholeCamera camera = test_camera();
  for (int trial = 0; trial < 5; ++trial) {
    const SE3 pose = random_pose(rng);
    const Vec3 point = random_visible_point(camera, pose, 1.0, 6.0, rng);
    const Vec3 p_cam = pose * point;
    const Vec2 pixel = camera.project(p_cam);
    const StereoReprojectionCost cost(CostCamera::from(camera), pixel, camera.right_u(pixel.x(), p_cam.z()) + 0.7,
                                      0.69);
    EXPECT_LT(max_jacobian_error<3>(cost, to_pose_block(pose), point), 1e-6);
  }
}

TEST(CeresPose, PlaneCostJacobiansMatchNumeric) {
  std::mt19937 rng(3);
  const PinholeCamera camera = test_camera();
  for (int trial = 0; trial < 5; ++trial) {
    const SE3 pose = random_pose(rng);
    const Vec3 point = random_visible_point(camera, pose, 1.0, 6.0, rng);
    const PlaneDistanceCost cost(random_unit(rng), 1.65, 0.05);
    EXPECT_LT(max_jacobian_error<1>(cost, to_pose_block(pose), point), 1e-6);
  }
}

TEST(CeresPose, PlaneResidualIsTheDistanceInSigmas) {
  // Camera at the origin looking along z, a point 2 m ahead and 1.5 m down; the plane y = 1.65 under the
  // camera: the point is 0.15 m above it, -3 sigmas at sigma 0.05.
  const PlaneDistanceCost cost(Vec3::UnitY(), 1.65, 0.05);
  PoseBlock block = to_pose_block(SE3());
  const Vec3 point(0.3, 1.5, 2.0);
  const double* parameters[] = {block.data(), point.data()};
  double residual[1];
  ASSERT_TRUE(cost.Evaluate(parameters, residual, nullptr));
  EXPECT_NEAR(residual[0], -3.0, 1e-9);
}

TEST(CeresPose, StereoResidualIsWeightedError) {
  const PinholeCamera camera = test_camera();
  const SE3 pose;
  const Vec3 point(0.5, -0.25, 2.0);
  const Vec2 pixel = camera.project(point);
  const double right_u = camera.right_u(pixel.x(), point.z());
  // Observation off by (1, -2, 3) px at inv_sigma2 = 4: residual = 2 * (predicted - observed).
  const StereoReprojectionCost cost(CostCamera::from(camera), pixel + Vec2(1.0, -2.0), right_u + 3.0, 4.0);
  PoseBlock block = to_pose_block(pose);
  const double* parameters[] = {block.data(), point.data()};
  double residual[3];
  ASSERT_TRUE(cost.Evaluate(parameters, residual, nullptr));
  EXPECT_NEAR(residual[0], -2.0, 1e-9);
  EXPECT_NEAR(residual[1], 4.0, 1e-9);
  EXPECT_NEAR(residual[2], -6.0, 1e-9);
}

TEST(CeresPose, ManifoldPlusMinusRoundTrip) {
  std::mt19937 rng(4);
  const Se3Manifold manifold;
  for (int trial = 0; trial < 10; ++trial) {
    const SE3 x = random_pose(rng);
    Vec6 delta;
    std::uniform_real_distribution<double> u(-0.3, 0.3);
    for (int i = 0; i < 6; ++i) delta(i) = u(rng);
    const PoseBlock xb = to_pose_block(x);
    PoseBlock yb;
    ASSERT_TRUE(manifold.Plus(xb.data(), delta.data(), yb.data()));
    // Plus is the same update the pose optimiser uses.
    const SE3 expected = left_update(delta, x);
    EXPECT_LT((from_pose_block(yb).translation() - expected.translation()).norm(), 1e-12);
    EXPECT_LT(rotation_error_rad(from_pose_block(yb), expected), 1e-9);
    Vec6 back;
    ASSERT_TRUE(manifold.Minus(yb.data(), xb.data(), back.data()));
    EXPECT_LT((back - delta).norm(), 1e-9);
  }
}
