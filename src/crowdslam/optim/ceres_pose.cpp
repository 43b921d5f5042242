#include "crowdslam/optim/ceres_pose.h"

#include <algorithm>
#include <cmath>

#include "crowdslam/optim/se3_update.h"

namespace crowdslam::optim {

using geometry::Mat3;
using geometry::SE3;
using geometry::Vec2;
using geometry::Vec3;
using geometry::Vec6;

namespace {

using ConstQuaternionMap = Eigen::Map<const Eigen::Quaterniond>;
using ConstVec3Map = Eigen::Map<const Vec3>;

// d residual / d (delta, point) of a camera-frame point; shared by both cost functions.
template <int kRows>
void write_jacobians(const Eigen::Matrix<double, kRows, 3>& d_residual_d_pcam, const Vec3& p_cam,
                     const Eigen::Quaterniond& rotation, double** jacobians) {
  if (jacobians == nullptr) return;
  if (jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, kRows, 7, Eigen::RowMajor>> j(jacobians[0]);
    j.template leftCols<6>() = d_residual_d_pcam * point_jacobian_wrt_pose(p_cam);
    j.col(6).setZero();
  }
  if (jacobians[1] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, kRows, 3, Eigen::RowMajor>> j(jacobians[1]);
    j = d_residual_d_pcam * rotation.toRotationMatrix();
  }
}

}  // namespace

PoseBlock to_pose_block(const SE3& cam_from_world) {
  PoseBlock block;
  const Eigen::Quaterniond& q = cam_from_world.rotation();
  block = {q.x(), q.y(), q.z(), q.w(), cam_from_world.translation().x(), cam_from_world.translation().y(),
           cam_from_world.translation().z()};
  return block;
}

SE3 from_pose_block(const PoseBlock& block) {
  return SE3(Eigen::Quaterniond(block[3], block[0], block[1], block[2]), Vec3(block[4], block[5], block[6]));
}

bool Se3Manifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  const ConstQuaternionMap q(x);
  const ConstVec3Map t(x + 4);
  const Mat3 d_rotation = geometry::so3_exp(ConstVec3Map(delta + 3));
  Eigen::Map<Eigen::Quaterniond> q_out(x_plus_delta);
  Eigen::Map<Vec3> t_out(x_plus_delta + 4);
  q_out = (Eigen::Quaterniond(d_rotation) * q).normalized();
  t_out = d_rotation * t + ConstVec3Map(delta);
  return true;
}

bool Se3Manifold::PlusJacobian(const double* /*x*/, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 7, 6, Eigen::RowMajor>> j(jacobian);
  j.setZero();
  j.topRows<6>().setIdentity();
  return true;
}

bool Se3Manifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  const Mat3 d_rotation = ConstQuaternionMap(y).toRotationMatrix() * ConstQuaternionMap(x).toRotationMatrix().transpose();
  Eigen::Map<Vec6> out(y_minus_x);
  out.tail<3>() = geometry::so3_log(d_rotation);
  out.head<3>() = ConstVec3Map(y + 4) - d_rotation * ConstVec3Map(x + 4);
  return true;
}

bool Se3Manifold::MinusJacobian(const double* /*x*/, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 6, 7, Eigen::RowMajor>> j(jacobian);
  j.setZero();
  j.leftCols<6>().setIdentity();
  return true;
}

MonoReprojectionCost::MonoReprojectionCost(const CostCamera& camera, const Vec2& pixel, double inv_sigma2)
    : camera_(camera), pixel_(pixel), sqrt_information_(std::sqrt(inv_sigma2)) {}

bool MonoReprojectionCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const ConstQuaternionMap q(parameters[0]);
  const Vec3 p_cam = q * ConstVec3Map(parameters[1]) + ConstVec3Map(parameters[0] + 4);
  if (std::abs(p_cam.z()) < kMinAbsDepth) return false;
  const double inv_z = 1.0 / p_cam.z();
  residuals[0] = sqrt_information_ * (camera_.fx * p_cam.x() * inv_z + camera_.cx - pixel_.x());
  residuals[1] = sqrt_information_ * (camera_.fy * p_cam.y() * inv_z + camera_.cy - pixel_.y());
  if (jacobians != nullptr) {
    const Mat23 d = sqrt_information_ * projection_jacobian(camera_.fx, camera_.fy, p_cam);
    write_jacobians<2>(d, p_cam, q, jacobians);
  }
  return true;
}

StereoReprojectionCost::StereoReprojectionCost(const CostCamera& camera, const Vec2& pixel, double right_u,
                                               double inv_sigma2)
    : camera_(camera), observed_(pixel.x(), pixel.y(), right_u), sqrt_information_(std::sqrt(inv_sigma2)) {}

bool StereoReprojectionCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const ConstQuaternionMap q(parameters[0]);
  const Vec3 p_cam = q * ConstVec3Map(parameters[1]) + ConstVec3Map(parameters[0] + 4);
  if (std::abs(p_cam.z()) < kMinAbsDepth) return false;
  const double inv_z = 1.0 / p_cam.z();
  const double u = camera_.fx * p_cam.x() * inv_z + camera_.cx;
  residuals[0] = sqrt_information_ * (u - observed_.x());
  residuals[1] = sqrt_information_ * (camera_.fy * p_cam.y() * inv_z + camera_.cy - observed_.y());
  residuals[2] = sqrt_information_ * (u - camera_.bf * inv_z - observed_.z());
  if (jacobians != nullptr) {
    Eigen::Matrix3d d;
    d.topRows<2>() = projection_jacobian(camera_.fx, camera_.fy, p_cam);
    d.row(2) = right_u_jacobian(camera_.fx, camera_.bf, p_cam);
    d *= sqrt_information_;
    write_jacobians<3>(d, p_cam, q, jacobians);
  }
  return true;
}

PlaneDistanceCost::PlaneDistanceCost(const Vec3& normal_cam, double distance, double sigma)
    : normal_(normal_cam), distance_(distance), inv_sigma_(1.0 / sigma) {}

bool PlaneDistanceCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const ConstQuaternionMap q(parameters[0]);
  const Vec3 p_cam = q * ConstVec3Map(parameters[1]) + ConstVec3Map(parameters[0] + 4);
  residuals[0] = inv_sigma_ * (normal_.dot(p_cam) - distance_);
  if (jacobians != nullptr) {
    const Eigen::Matrix<double, 1, 3> d = inv_sigma_ * normal_.transpose();
    write_jacobians<1>(d, p_cam, q, jacobians);
  }
  return true;
}

RelativePoseCost::RelativePoseCost(const SE3& a_from_b, const Vec6& weight)
    : a_from_b_(a_from_b), sqrt_weight_(weight.cwiseSqrt()) {}

bool RelativePoseCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  PoseBlock a;
  PoseBlock b;
  std::copy(parameters[0], parameters[0] + 7, a.begin());
  std::copy(parameters[1], parameters[1] + 7, b.begin());
  Eigen::Matrix<double, 6, 6> j_b;
  const Vec6 e = relative_pose_error(from_pose_block(a), from_pose_block(b), a_from_b_, &j_b);
  Eigen::Map<Vec6> r(residuals);
  r = sqrt_weight_.cwiseProduct(e);
  using Jacobian = Eigen::Matrix<double, 6, 7, Eigen::RowMajor>;
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Eigen::Map<Jacobian> j(jacobians[0]);
    j.setZero();
    j.leftCols<6>().diagonal() = sqrt_weight_;
  }
  if (jacobians != nullptr && jacobians[1] != nullptr) {
    Eigen::Map<Jacobian> j(jacobians[1]);
    j.setZero();
    j.leftCols<6>() = sqrt_weight_.asDiagonal() * j_b;
  }
  return true;
}

}  // namespace crowdslam::optim
