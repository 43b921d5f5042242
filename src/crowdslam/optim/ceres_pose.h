#pragma once
// Ceres building blocks for problems with cam_from_world poses and 3D points.
//
// A pose parameter block is 7 doubles: Eigen quaternion coefficients (x, y, z, w) then the
// translation, for cam_from_world. Se3Manifold updates it by left perturbation with a 6-vector
// (rho, phi) exactly like optim::left_update (se3_update.h).
//
// Jacobian convention (as in VINS/OKVIS "local parameterisation" code): the cost functions below
// write d residual / d delta into the first 6 columns of their 7-column pose Jacobian and zero in
// the last one, and Se3Manifold::PlusJacobian returns [I6; 0]. Ceres multiplies the two, so the
// solver sees the exact tangent-space Jacobian without differentiating the quaternion. These cost
// functions must only be used with Se3Manifold on their pose block.
#include <array>
#include <ceres/manifold.h>
#include <ceres/sized_cost_function.h>

#include "crowdslam/geometry/camera.h"
#include "crowdslam/geometry/se3.h"

namespace crowdslam::optim {

using PoseBlock = std::array<double, 7>;

PoseBlock to_pose_block(const geometry::SE3& cam_from_world);
geometry::SE3 from_pose_block(const PoseBlock& block);

class Se3Manifold final : public ceres::Manifold {
 public:
  [[nodiscard]] int AmbientSize() const override { return 7; }
  [[nodiscard]] int TangentSize() const override { return 6; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

// Intrinsics the cost functions need (no distortion: observations are undistorted pixels).
struct CostCamera {
  double fx = 0.0;
  double fy = 0.0;
  double cx = 0.0;
  double cy = 0.0;
  double bf = 0.0;
  static CostCamera from(const geometry::PinholeCamera& camera) {
    return {camera.fx, camera.fy, camera.cx, camera.cy, camera.bf};
  }
};

// Residual sqrt(inv_sigma2) * (project(cam_from_world * point) - pixel); blocks: pose (7), point (3).
class MonoReprojectionCost final : public ceres::SizedCostFunction<2, 7, 3> {
 public:
  MonoReprojectionCost(const CostCamera& camera, const geometry::Vec2& pixel, double inv_sigma2);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  CostCamera camera_;
  geometry::Vec2 pixel_;
  double sqrt_information_;
};

// As MonoReprojectionCost plus the right-image coordinate u - bf / z against right_u.
class StereoReprojectionCost final : public ceres::SizedCostFunction<3, 7, 3> {
 public:
  StereoReprojectionCost(const CostCamera& camera, const geometry::Vec2& pixel, double right_u, double inv_sigma2);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  CostCamera camera_;
  geometry::Vec3 observed_;  // u, v, u_r
  double sqrt_information_;
};

// Residual (normal . (cam_from_world * point) - distance) / sigma: a point on a plane given in the camera
// frame (BaPlaneConstraint); blocks: pose (7), point (3).
class PlaneDistanceCost final : public ceres::SizedCostFunction<1, 7, 3> {
 public:
  PlaneDistanceCost(const geometry::Vec3& normal_cam, double distance, double sigma);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  geometry::Vec3 normal_;
  double distance_;
  double inv_sigma_;
};

// Residual sqrt(weight) .* relative_pose_error(a, b, a_from_b) (se3_update.h): a measured relative pose
// between two keyframes (BaRelativePose); blocks: pose a (7), pose b (7).
class RelativePoseCost final : public ceres::SizedCostFunction<6, 7, 7> {
 public:
  RelativePoseCost(const geometry::SE3& a_from_b, const geometry::Vec6& weight);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  geometry::SE3 a_from_b_;
  geometry::Vec6 sqrt_weight_;
};

}  // namespace crowdslam::optim
