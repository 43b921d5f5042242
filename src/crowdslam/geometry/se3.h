#pragma once
// Rigid-body transforms on Eigen.
//
// Naming convention (COLMAP style): a transform is named by the frames it maps between,
// `cam_from_world` maps world coordinates into the camera frame; `world_from_cam` is its inverse.
// Composition reads right to left: a_from_c = a_from_b * b_from_c.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace crowdslam::geometry {

using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat3 = Eigen::Matrix3d;
using Mat4 = Eigen::Matrix4d;

class SE3 {
 public:
  SE3() : rotation_(Eigen::Quaterniond::Identity()), translation_(Vec3::Zero()) {}
  SE3(const Eigen::Quaterniond& rotation, const Vec3& translation)
      : rotation_(rotation.normalized()), translation_(translation) {}
  SE3(const Mat3& rotation, const Vec3& translation)
      : rotation_(Eigen::Quaterniond(rotation).normalized()), translation_(translation) {}
  explicit SE3(const Mat4& matrix)
      : SE3(Mat3(matrix.topLeftCorner<3, 3>()), Vec3(matrix.topRightCorner<3, 1>())) {}

  static SE3 identity() { return SE3(); }
  // A rotation that is already a unit quaternion, kept bit for bit (saved maps reload exactly).
  static SE3 from_unit_quaternion(const Eigen::Quaterniond& rotation, const Vec3& translation) {
    SE3 pose;
    pose.rotation_ = rotation;
    pose.translation_ = translation;
    return pose;
  }
  // Exponential map of a twist (rho, phi): translation part first, rotation part second.
  static SE3 exp(const Vec6& twist);
  // Inverse of exp.
  [[nodiscard]] Vec6 log() const;

  [[nodiscard]] const Eigen::Quaterniond& rotation() const { return rotation_; }
  [[nodiscard]] Mat3 rotation_matrix() const { return rotation_.toRotationMatrix(); }
  [[nodiscard]] const Vec3& translation() const { return translation_; }
  [[nodiscard]] Mat4 matrix() const;

  [[nodiscard]] SE3 inverse() const {
    const Eigen::Quaterniond inv = rotation_.conjugate();
    return SE3(inv, -(inv * translation_));
  }
  SE3 operator*(const SE3& other) const {
    return SE3(rotation_ * other.rotation_, rotation_ * other.translation_ + translation_);
  }
  Vec3 operator*(const Vec3& point) const { return rotation_ * point + translation_; }

 private:
  Eigen::Quaterniond rotation_;
  Vec3 translation_;
};

// SO(3) helpers.
Mat3 skew(const Vec3& v);
Mat3 so3_exp(const Vec3& phi);
Vec3 so3_log(const Mat3& rotation);
// Rotation angle of a rotation matrix in radians, robust near 0 and pi.
double rotation_angle(const Mat3& rotation);

}  // namespace crowdslam::geometry
