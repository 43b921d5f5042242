#pragma once
// Left-perturbation update and reprojection Jacobians shared by the pose optimiser and the
// bundle-adjustment cost functions.
//
// Update: for d = (rho, phi), R' = Exp(phi) R and t' = Exp(phi) t + rho, so a camera-frame point
// moves as p_cam' = Exp(phi) p_cam + rho and d p_cam / d d = [I, -skew(p_cam)] at d = 0.
// (Same first-order behaviour as cam_from_world <- SE3::exp(d) * cam_from_world, cheaper.)
#include <Eigen/Core>

#include "crowdslam/geometry/camera.h"
#include "crowdslam/geometry/se3.h"

namespace crowdslam::optim {

using Mat23 = Eigen::Matrix<double, 2, 3>;
using Mat26 = Eigen::Matrix<double, 2, 6>;
using Mat36 = Eigen::Matrix<double, 3, 6>;

// Points nearer than this to the camera plane are not projected (every reprojection cost and the Schur
// LM report them as invalid).
inline constexpr double kMinAbsDepth = 1e-12;

inline geometry::SE3 left_update(const geometry::Vec6& delta, const geometry::SE3& cam_from_world) {
  const geometry::Mat3 d_rotation = geometry::so3_exp(delta.tail<3>());
  const Eigen::Quaterniond dq(d_rotation);
  return geometry::SE3(dq * cam_from_world.rotation(), d_rotation * cam_from_world.translation() + delta.head<3>());
}

// d (u, v) / d p_cam for the pinhole projection.
inline Mat23 projection_jacobian(double fx, double fy, const geometry::Vec3& p_cam) {
  const double inv_z = 1.0 / p_cam.z();
  const double inv_z2 = inv_z * inv_z;
  Mat23 j;
  j << fx * inv_z, 0.0, -fx * p_cam.x() * inv_z2, 0.0, fy * inv_z, -fy * p_cam.y() * inv_z2;
  return j;
}

// d p_cam / d delta = [I, -skew(p_cam)].
inline Eigen::Matrix<double, 3, 6> point_jacobian_wrt_pose(const geometry::Vec3& p_cam) {
  Eigen::Matrix<double, 3, 6> j;
  j.leftCols<3>().setIdentity();
  j.rightCols<3>() = -geometry::skew(p_cam);
  return j;
}

// d u_r / d p_cam for u_r = fx x / z + cx - bf / z.
inline Eigen::RowVector3d right_u_jacobian(double fx, double bf, const geometry::Vec3& p_cam) {
  const double inv_z = 1.0 / p_cam.z();
  const double inv_z2 = inv_z * inv_z;
  return {fx * inv_z, 0.0, -fx * p_cam.x() * inv_z2 + bf * inv_z2};
}

// Error of a measured relative pose a_from_b between cam_from_world poses a and b: the translation and
// so3 log of a * b^-1 * a_from_b^-1. Under left updates of a and b its Jacobians are I (pose a) and
// -Ad(a * b^-1) = -[[R, [t]x R], [0, R]] (pose b), (rho, phi) order, exact at zero error.
inline geometry::Vec6 relative_pose_error(const geometry::SE3& a, const geometry::SE3& b,
                                          const geometry::SE3& a_from_b,
                                          Eigen::Matrix<double, 6, 6>* jacobian_b = nullptr) {
  const geometry::SE3 measured_b = a * b.inverse();
  const geometry::SE3 error = measured_b * a_from_b.inverse();
  geometry::Vec6 e;
  e.head<3>() = error.translation();
  e.tail<3>() = geometry::so3_log(error.rotation_matrix());
  if (jacobian_b != nullptr) {
    const geometry::Mat3 rotation = measured_b.rotation_matrix();
    jacobian_b->setZero();
    jacobian_b->topLeftCorner<3, 3>() = -rotation;
    jacobian_b->topRightCorner<3, 3>() = -geometry::skew(measured_b.translation()) * rotation;
    jacobian_b->bottomRightCorner<3, 3>() = -rotation;
  }
  return e;
}

}  // namespace crowdslam::optim
