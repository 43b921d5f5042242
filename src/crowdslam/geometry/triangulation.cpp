#include "crowdslam/geometry/triangulation.h"

#include <Eigen/SVD>
#include <cmath>
#include <limits>

namespace crowdslam::geometry {

Mat34 projection_matrix(const SE3& cam_from_world) {
  Mat34 p;
  p.leftCols<3>() = cam_from_world.rotation_matrix();
  p.col(3) = cam_from_world.translation();
  return p;
}

std::optional<Vec3> triangulate_dlt(const Mat34& projection1, const Vec2& point1, const Mat34& projection2,
                                    const Vec2& point2) {
  // x * (p3 . X) - (p1 . X) = 0 and y * (p3 . X) - (p2 . X) = 0 for each view.
  Eigen::Matrix4d a;
  a.row(0) = point1.x() * projection1.row(2) - projection1.row(0);
  a.row(1) = point1.y() * projection1.row(2) - projection1.row(1);
  a.row(2) = point2.x() * projection2.row(2) - projection2.row(0);
  a.row(3) = point2.y() * projection2.row(2) - projection2.row(1);
  // Row scaling does not change the null space but improves conditioning.
  for (int r = 0; r < 4; ++r) {
    const double n = a.row(r).norm();
    if (n > 0.0) a.row(r) /= n;
  }
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(a, Eigen::ComputeFullV);
  const Eigen::Vector4d x = svd.matrixV().col(3);
  if (std::abs(x(3)) < 1e-12) return std::nullopt;  // x has unit norm
  const Vec3 point = x.head<3>() / x(3);
  if (!point.allFinite()) return std::nullopt;
  return point;
}

std::optional<Vec3> triangulate_normalized(const SE3& cam1_from_world, const Vec2& normalized1,
                                           const SE3& cam2_from_world, const Vec2& normalized2) {
  return triangulate_dlt(projection_matrix(cam1_from_world), normalized1, projection_matrix(cam2_from_world),
                         normalized2);
}

std::optional<Vec3> triangulate_pixels(const PinholeCamera& camera1, const SE3& cam1_from_world, const Vec2& pixel1,
                                       const PinholeCamera& camera2, const SE3& cam2_from_world, const Vec2& pixel2) {
  return triangulate_normalized(cam1_from_world, camera1.normalize(pixel1), cam2_from_world, camera2.normalize(pixel2));
}

double ray_parallax_cosine(const SE3& cam1_from_world, const Vec2& normalized1, const SE3& cam2_from_world,
                           const Vec2& normalized2) {
  // Rays rotated into the world frame: world_from_cam rotation = R^T.
  const Vec3 ray1 = cam1_from_world.rotation().conjugate() * Vec3(normalized1.x(), normalized1.y(), 1.0);
  const Vec3 ray2 = cam2_from_world.rotation().conjugate() * Vec3(normalized2.x(), normalized2.y(), 1.0);
  return ray1.dot(ray2) / (ray1.norm() * ray2.norm());
}

double point_parallax_cosine(const Vec3& point_world, const Vec3& center1_world, const Vec3& center2_world) {
  const Vec3 d1 = point_world - center1_world;
  const Vec3 d2 = point_world - center2_world;
  return d1.dot(d2) / (d1.norm() * d2.norm());
}

double reprojection_error_squared(const PinholeCamera& camera, const SE3& cam_from_world, const Vec3& point_world,
                                  const Vec2& pixel, double right_u) {
  const Vec3 p = cam_from_world * point_world;
  if (!(p.z() > 0.0)) return std::numeric_limits<double>::infinity();
  const Vec2 predicted = camera.project(p);
  double error2 = (predicted - pixel).squaredNorm();
  if (right_u >= 0.0 && camera.is_stereo()) {
    const double du = camera.right_u(predicted.x(), p.z()) - right_u;
    error2 += du * du;
  }
  return error2;
}

bool reprojection_within_threshold(const PinholeCamera& camera, const SE3& cam_from_world, const Vec3& point_world,
                                   const Vec2& pixel, double level_sigma2, double right_u) {
  const bool stereo = right_u >= 0.0 && camera.is_stereo();
  const double chi2 = stereo ? kChi2Stereo : kChi2Mono;
  return reprojection_error_squared(camera, cam_from_world, point_world, pixel, right_u) <= chi2 * level_sigma2;
}

}  // namespace crowdslam::geometry
