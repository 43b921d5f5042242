#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "crowdslam/geometry/triangulation.h"

using namespace crowdslam::geometry;

namespace {

PinholeCamera test_camera() {
  PinholeCamera camera;
  camera.fx = 520.0;
  camera.fy = 515.0;
  camera.cx = 320.0;
  camera.cy = 240.0;
  camera.width = 640;
  camera.height = 480;
  camera.bf = 0.1 * 520.0;
  return camera;
}

// Camera at `center` (world), looking along +z of the world rotated by `yaw` about y.
SE3 camera_at(const Vec3& center, double yaw) {
  const Mat3 world_from_cam = Eigen::AngleAxisd(yaw, Vec3::UnitY()).toRotationMatrix();
  return SE3(world_from_cam, center).inverse();
}

}  // namespace

TEST(Triangulation, ExactPointFromTwoViews) {
  const PinholeCamera camera = test_camera();
  const SE3 cam1 = camera_at(Vec3(0, 0, 0), 0.0);
  const SE3 cam2 = camera_at(Vec3(0.5, 0.1, 0.0), -0.1);
  const Vec3 point(0.3, -0.4, 4.0);
  const Vec2 px1 = camera.project(cam1 * point);
  const Vec2 px2 = camera.project(cam2 * point);
  const auto estimate = triangulate_pixels(camera, cam1, px1, camera, cam2, px2);
  ASSERT_TRUE(estimate.has_value());
  EXPECT_LT((*estimate - point).norm(), 1e-9);

  // Same with pixel projection matrices K[R|t].
  const Mat3 k = camera.intrinsic_matrix();
  const auto from_pixels = triangulate_dlt(k * projection_matrix(cam1), px1, k * projection_matrix(cam2), px2);
  ASSERT_TRUE(from_pixels.has_value());
  EXPECT_LT((*from_pixels - point).norm(), 1e-9);
}

TEST(Triangulation, NoisyPixelsErrorMatchesDepthUncertainty) {
  // Sideways baseline b, depth z, focal f: 1 px disparity noise -> depth std ~ z^2 / (f b).
  const PinholeCamera camera = test_camera();
  const SE3 cam1 = camera_at(Vec3(0, 0, 0), 0.0);
  const SE3 cam2 = camera_at(Vec3(0.4, 0, 0), 0.0);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> lateral(-1.0, 1.0);
  const double depth = 3.0;
  double sum_sq_depth_error = 0.0;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    const Vec3 point(lateral(rng), lateral(rng) * 0.7, depth);
    const Vec2 px1 = camera.project(cam1 * point) + Vec2(noise(rng), noise(rng));
    const Vec2 px2 = camera.project(cam2 * point) + Vec2(noise(rng), noise(rng));
    const auto estimate = triangulate_pixels(camera, cam1, px1, camera, cam2, px2);
    ASSERT_TRUE(estimate.has_value());
    const double e = estimate->z() - depth;
    sum_sq_depth_error += e * e;
  }
  const double rms = std::sqrt(sum_sq_depth_error / n);
  // Disparity noise is sqrt(2) px (independent noise in both u's).
  const double expected = depth * depth / (camera.fx * 0.4) * std::sqrt(2.0);
  EXPECT_NEAR(rms, expected, 0.15 * expected);
}

TEST(Triangulation, ParallelRaysGiveNoPointOrFarPoint) {
  const SE3 cam1 = camera_at(Vec3(0, 0, 0), 0.0);
  const SE3 cam2 = camera_at(Vec3(0.5, 0, 0), 0.0);
  // Same normalised coordinate in both views: rays parallel, point at infinity.
  const Vec2 n(0.1, 0.05);
  const auto estimate = triangulate_normalized(cam1, n, cam2, n);
  if (estimate.has_value()) {
    EXPECT_GT(estimate->norm(), 1e6);
  }
  EXPECT_NEAR(ray_parallax_cosine(cam1, n, cam2, n), 1.0, 1e-12);
}

TEST(Triangulation, ParallaxCosines) {
  // Centres at (-1,0,0) and (1,0,0), point at (0,0,1): rays at +-45 degrees, angle 90 degrees.
  const Vec3 point(0, 0, 1);
  EXPECT_NEAR(point_parallax_cosine(point, Vec3(-1, 0, 0), Vec3(1, 0, 0)), 0.0, 1e-12);
  const SE3 cam1 = camera_at(Vec3(-1, 0, 0), 0.0);
  const SE3 cam2 = camera_at(Vec3(1, 0, 0), 0.0);
  const Vec3 p1 = cam1 * point;
  const Vec3 p2 = cam2 * point;
  const double c = ray_parallax_cosine(cam1, p1.head<2>() / p1.z(), cam2, p2.head<2>() / p2.z());
  EXPECT_NEAR(c, 0.0, 1e-12);
  // Rotated cameras: the ray cosine is computed in the world frame, so rotating a camera while
  // keeping the image point consistent does not change it.
  const SE3 cam2_rot = camera_at(Vec3(1, 0, 0), -0.3);
  const Vec3 p2r = cam2_rot * point;
  EXPECT_NEAR(ray_parallax_cosine(cam1, p1.head<2>() / p1.z(), cam2_rot, p2r.head<2>() / p2r.z()), 0.0, 1e-12);
}

TEST(Triangulation, DepthSign) {
  const SE3 cam = camera_at(Vec3(0, 0, 0), M_PI);  // looking along -z of the world
  EXPECT_TRUE(has_positive_depth(cam, Vec3(0, 0, -2)));
  EXPECT_FALSE(has_positive_depth(cam, Vec3(0, 0, 2)));
  EXPECT_NEAR(depth_in_camera(cam, Vec3(0.3, 0, -2)), 2.0, 1e-12);
}

TEST(Triangulation, ReprojectionThresholdScalesWithLevelSigma) {
  const PinholeCamera camera = test_camera();
  const SE3 cam = camera_at(Vec3(0, 0, 0), 0.0);
  const Vec3 point(0.2, 0.1, 2.0);
  const Vec2 pixel = camera.project(point);
  // 2.5 px off: error^2 = 6.25 > 5.991 at level 0 (sigma2 = 1), accepted at level 1 (sigma2 = 1.44).
  const Vec2 off = pixel + Vec2(2.5, 0.0);
  EXPECT_NEAR(reprojection_error_squared(camera, cam, point, off), 6.25, 1e-9);
  EXPECT_FALSE(reprojection_within_threshold(camera, cam, point, off, 1.0));
  EXPECT_TRUE(reprojection_within_threshold(camera, cam, point, off, 1.44));

  // Stereo: right coordinate 1 px off adds 1 to the error and uses the 3-dof threshold 7.815.
  const double ur = camera.right_u(pixel.x(), point.z());
  EXPECT_NEAR(reprojection_error_squared(camera, cam, point, off, ur + 1.0), 7.25, 1e-9);
  EXPECT_TRUE(reprojection_within_threshold(camera, cam, point, off, 1.0, ur + 1.0));
  EXPECT_FALSE(reprojection_within_threshold(camera, cam, point, off, 1.0, ur + 1.5));

  // Behind the camera: never within threshold.
  EXPECT_TRUE(std::isinf(reprojection_error_squared(camera, cam, Vec3(0, 0, -1), pixel)));
  EXPECT_FALSE(reprojection_within_threshold(camera, cam, Vec3(0, 0, -1), pixel, 100.0));
}
