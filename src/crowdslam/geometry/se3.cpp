#include "crowdslam/geometry/se3.h"

#include <algorithm>
#include <cmath>

namespace crowdslam::geometry {

Mat3 skew(const Vec3& v) {
  Mat3 m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Mat3 so3_exp(const Vec3& phi) {
  const double angle = phi.norm();
  if (angle < 1e-12) return Mat3::Identity() + skew(phi);
  return Eigen::AngleAxisd(angle, phi / angle).toRotationMatrix();
}

Vec3 so3_log(const Mat3& rotation) {
  const Eigen::AngleAxisd aa(rotation);
  return aa.angle() * aa.axis();
}

double rotation_angle(const Mat3& rotation) {
  const double c = std::clamp((rotation.trace() - 1.0) * 0.5, -1.0, 1.0);
  return std::acos(c);
}

namespace {
// Left Jacobian of SO(3) and its inverse, used by the SE(3) exponential and logarithm.
Mat3 left_jacobian(const Vec3& phi) {
  const double theta = phi.norm();
  const Mat3 k = skew(phi);
  if (theta < 1e-8) return Mat3::Identity() + 0.5 * k;
  const double t2 = theta * theta;
  return Mat3::Identity() + (1 - std::cos(theta)) / t2 * k + (theta - std::sin(theta)) / (t2 * theta) * k * k;
}
}  // namespace

SE3 SE3::exp(const Vec6& twist) {
  const Vec3 rho = twist.head<3>();
  const Vec3 phi = twist.tail<3>();
  return SE3(so3_exp(phi), left_jacobian(phi) * rho);
}

Vec6 SE3::log() const {
  const Vec3 phi = so3_log(rotation_matrix());
  Vec6 twist;
  twist.head<3>() = left_jacobian(phi).inverse() * translation_;
  twist.tail<3>() = phi;
  return twist;
}

Mat4 SE3::matrix() const {
  Mat4 m = Mat4::Identity();
  m.topLeftCorner<3, 3>() = rotation_matrix();
  m.topRightCorner<3, 1>() = translation_;
  return m;
}

}  // namespace crowdslam::geometry
