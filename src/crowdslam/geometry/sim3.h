#pragma once
// Similarity transforms (rotation, translation, scale) for loop closing: x' = s R x + t.
// Named like SE3: `cam1_from_cam2` maps camera-2 coordinates into camera 1. An SE3 is a Sim3 with s = 1.
// Composition reads right to left: a_from_c = a_from_b * b_from_c.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "crowdslam/geometry/se3.h"

namespace crowdslam::geometry {

// Tangent vector of Sim3: (rho, phi, sigma) = translation part, rotation vector, log of the scale.
using Vec7 = Eigen::Matrix<double, 7, 1>;

class Sim3 {
 public:
  Sim3() : rotation_(Eigen::Quaterniond::Identity()), translation_(Vec3::Zero()) {}
  Sim3(const Eigen::Quaterniond& rotation, const Vec3& translation, double scale)
      : rotation_(rotation.normalized()), translation_(translation), scale_(scale) {}
  Sim3(const Mat3& rotation, const Vec3& translation, double scale)
      : Sim3(Eigen::Quaterniond(rotation), translation, scale) {}
  explicit Sim3(const SE3& rigid) : Sim3(rigid.rotation(), rigid.translation(), 1.0) {}

  static Sim3 identity() { return Sim3(); }
  // Exponential map of sim(3): R = Exp(phi), s = e^sigma, t = W(phi, sigma) rho with
  // W = integral_0^1 e^(sigma u) Exp(u phi) du. With sigma = 0 it equals SE3::exp((rho, phi)).
  static Sim3 exp(const Vec7& tangent);
  // Inverse of exp (rotation angle in [0, pi]).
  [[nodiscard]] Vec7 log() const;

  [[nodiscard]] const Eigen::Quaterniond& rotation() const { return rotation_; }
  [[nodiscard]] Mat3 rotation_matrix() const { return rotation_.toRotationMatrix(); }
  [[nodiscard]] const Vec3& translation() const { return translation_; }
  [[nodiscard]] double scale() const { return scale_; }

  [[nodiscard]] Sim3 inverse() const {
    const Eigen::Quaterniond inv = rotation_.conjugate();
    return Sim3(inv, -(inv * translation_) / scale_, 1.0 / scale_);
  }
  Sim3 operator*(const Sim3& other) const {
    return Sim3(rotation_ * other.rotation_, scale_ * (rotation_ * other.translation_) + translation_,
                scale_ * other.scale_);
  }
  Vec3 operator*(const Vec3& point) const { return scale_ * (rotation_ * point) + translation_; }

  // The rigid pose a corrected cam_from_world Sim3 stands for (ORB-SLAM: [R | t/s]): a point's camera
  // coordinates under this Sim3, divided by s.
  [[nodiscard]] SE3 to_se3() const { return SE3(rotation_, translation_ / scale_); }

 private:
  Eigen::Quaterniond rotation_;
  Vec3 translation_;
  double scale_ = 1.0;
};

}  // namespace crowdslam::geometry
