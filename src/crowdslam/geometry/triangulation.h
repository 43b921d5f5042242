#pragma once
// Two-view linear triangulation and the checks the local mapper applies to a new point.
//
// triangulate_dlt solves A X = 0 (4x4, two rows per view) by SVD and de-homogenises the right
// singular vector of the smallest singular value. The checks are separate small functions so the
// mapper can order them (cheap parallax first, triangulation, then depth and reprojection).
#include <Eigen/Core>
#include <optional>

#include "crowdslam/geometry/camera.h"
#include "crowdslam/geometry/se3.h"

namespace crowdslam::geometry {

using Mat34 = Eigen::Matrix<double, 3, 4>;

// Chi-square 95% quantiles for 2 (mono) and 3 (stereo: u, v, u_r) degrees of freedom.
inline constexpr double kChi2Mono = 5.991;
inline constexpr double kChi2Stereo = 7.815;

// [R | t] of a cam_from_world transform.
Mat34 projection_matrix(const SE3& cam_from_world);

// Linear triangulation from two 3x4 projection matrices and the matching image points
// (normalised coordinates with [R|t], or pixels with K[R|t]). Returns nullopt when the
// solution is at infinity (homogeneous w ~ 0) or not finite.
std::optional<Vec3> triangulate_dlt(const Mat34& projection1, const Vec2& point1, const Mat34& projection2,
                                    const Vec2& point2);

// Convenience: normalised coordinates (x/z, y/z) in each camera.
std::optional<Vec3> triangulate_normalized(const SE3& cam1_from_world, const Vec2& normalized1,
                                           const SE3& cam2_from_world, const Vec2& normalized2);

// Convenience: undistorted pixels seen by two (possibly different) pinhole cameras.
std::optional<Vec3> triangulate_pixels(const PinholeCamera& camera1, const SE3& cam1_from_world, const Vec2& pixel1,
                                       const PinholeCamera& camera2, const SE3& cam2_from_world, const Vec2& pixel2);

// Depth (z in the camera frame) of a world point.
inline double depth_in_camera(const SE3& cam_from_world, const Vec3& point_world) {
  return (cam_from_world * point_world).z();
}
inline bool has_positive_depth(const SE3& cam_from_world, const Vec3& point_world) {
  return depth_in_camera(cam_from_world, point_world) > 0.0;
}

// Cosine of the angle between the viewing rays of two normalised image points, both expressed in
// the world frame (the ray parallax the mapper checks before triangulating).
double ray_parallax_cosine(const SE3& cam1_from_world, const Vec2& normalized1, const SE3& cam2_from_world,
                           const Vec2& normalized2);

// Cosine of the angle at a world point between the directions to two camera centres.
double point_parallax_cosine(const Vec3& point_world, const Vec3& center1_world, const Vec3& center2_world);

// Squared reprojection error in pixels^2 (u, v; plus u_r when right_u >= 0 and the camera is stereo).
// Points at or behind the camera give +infinity.
double reprojection_error_squared(const PinholeCamera& camera, const SE3& cam_from_world, const Vec3& point_world,
                                  const Vec2& pixel, double right_u = -1.0);

// Reprojection test of one view: error^2 <= chi2 * sigma2 of the keypoint's pyramid level, with
// chi2 = kChi2Mono for a mono observation (right_u < 0) and kChi2Stereo for a stereo one.
bool reprojection_within_threshold(const PinholeCamera& camera, const SE3& cam_from_world, const Vec3& point_world,
                                   const Vec2& pixel, double level_sigma2, double right_u = -1.0);

}  // namespace crowdslam::geometry
