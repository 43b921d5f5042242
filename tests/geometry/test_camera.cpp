#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <random>

#include "crowdslam/geometry/camera.h"
#include "crowdslam/util/error.h"

using namespace crowdslam::geometry;

namespace {

PinholeCamera tum1_like() {
  PinholeCamera camera;
  camera.fx = 517.306408;
  camera.fy = 516.469215;
  camera.cx = 318.643040;
  camera.cy = 255.313989;
  camera.distortion = {0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  camera.width = 640;
  camera.height = 480;
  camera.bf = 40.0;
  return camera;
}

PinholeCamera ideal() {
  PinholeCamera camera = tum1_like();
  camera.distortion = Distortion{};
  return camera;
}

}  // namespace

TEST(PinholeCamera, ProjectUnprojectRoundTrip) {
  const PinholeCamera camera = ideal();
  const Vec3 point(0.3, -0.2, 2.5);
  const Vec2 pixel = camera.project(point);
  EXPECT_NEAR(pixel.x(), camera.fx * 0.3 / 2.5 + camera.cx, 1e-12);
  EXPECT_NEAR(pixel.y(), camera.fy * -0.2 / 2.5 + camera.cy, 1e-12);
  EXPECT_LT((camera.unproject(pixel, 2.5) - point).norm(), 1e-12);
  const Vec2 n = camera.normalize(pixel);
  EXPECT_NEAR(n.x(), 0.3 / 2.5, 1e-12);
  EXPECT_NEAR(n.y(), -0.2 / 2.5, 1e-12);
}

TEST(PinholeCamera, RightCoordinateFromBaseline) {
  const PinholeCamera camera = ideal();
  // A point at depth z seen by a right camera translated by the baseline along +x.
  const Vec3 point(0.4, 0.1, 2.0);
  const double baseline = camera.bf / camera.fx;
  const double u_right = camera.fx * (point.x() - baseline) / point.z() + camera.cx;
  EXPECT_NEAR(camera.right_u(camera.project(point).x(), point.z()), u_right, 1e-9);
  EXPECT_NEAR(camera.baseline_m(), baseline, 1e-15);
}

TEST(PinholeCamera, UndistortMatchesProjectPoints) {
  const PinholeCamera camera = tum1_like();
  // Ideal pinhole pixels of random points -> distort them with cv::projectPoints -> undistort back.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(-0.5, 0.5);
  std::uniform_real_distribution<double> uy(-0.4, 0.4);
  std::vector<cv::Point3d> points;
  std::vector<Vec2> ideal_pixels;
  for (int i = 0; i < 200; ++i) {
    const Vec3 p(ux(rng), uy(rng), 1.0);
    points.emplace_back(p.x(), p.y(), p.z());
    ideal_pixels.push_back(camera.project(p));
  }
  const cv::Mat k = (cv::Mat_<double>(3, 3) << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  const cv::Mat dist = (cv::Mat_<double>(1, 5) << camera.distortion.k1, camera.distortion.k2, camera.distortion.p1,
                        camera.distortion.p2, camera.distortion.k3);
  std::vector<cv::Point2d> distorted;
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), k, dist, distorted);

  std::vector<Vec2> distorted_eigen;
  std::vector<cv::Point2f> distorted_float;
  double max_shift = 0.0;
  for (std::size_t i = 0; i < distorted.size(); ++i) {
    distorted_eigen.emplace_back(distorted[i].x, distorted[i].y);
    distorted_float.emplace_back(static_cast<float>(distorted[i].x), static_cast<float>(distorted[i].y));
    max_shift = std::max(max_shift, (distorted_eigen.back() - ideal_pixels[i]).norm());
  }
  ASSERT_GT(max_shift, 2.0) << "distortion too weak for a meaningful test";

  const std::vector<Vec2> undistorted = camera.undistort_points(distorted_eigen);
  const std::vector<cv::Point2f> undistorted_float = camera.undistort_points(distorted_float);
  ASSERT_EQ(undistorted.size(), ideal_pixels.size());
  ASSERT_EQ(undistorted_float.size(), ideal_pixels.size());
  for (std::size_t i = 0; i < ideal_pixels.size(); ++i) {
    // OpenCV undistorts iteratively (default 5 iterations): sub-pixel, not exact.
    EXPECT_LT((undistorted[i] - ideal_pixels[i]).norm(), 0.05) << i;
    EXPECT_LT((Vec2(undistorted_float[i].x, undistorted_float[i].y) - ideal_pixels[i]).norm(), 0.05) << i;
  }
}

TEST(PinholeCamera, NoDistortionIsIdentity) {
  const PinholeCamera camera = ideal();
  const std::vector<Vec2> pixels{{10.25, 20.5}, {639.0, 0.0}};
  const std::vector<Vec2> out = camera.undistort_points(pixels);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0], pixels[0]);
  EXPECT_EQ(out[1], pixels[1]);
  const ImageBounds b = camera.undistorted_bounds();
  EXPECT_EQ(b.min_x, 0.0);
  EXPECT_EQ(b.max_x, 640.0);
  EXPECT_EQ(b.min_y, 0.0);
  EXPECT_EQ(b.max_y, 480.0);
}

TEST(PinholeCamera, UndistortedBoundsFromCorners) {
  const PinholeCamera camera = tum1_like();
  const ImageBounds b = camera.undistorted_bounds();
  const std::vector<Vec2> corners =
      camera.undistort_points(std::vector<Vec2>{{0, 0}, {640, 0}, {0, 480}, {640, 480}});
  EXPECT_DOUBLE_EQ(b.min_x, std::min(corners[0].x(), corners[2].x()));
  EXPECT_DOUBLE_EQ(b.max_x, std::max(corners[1].x(), corners[3].x()));
  EXPECT_DOUBLE_EQ(b.min_y, std::min(corners[0].y(), corners[1].y()));
  EXPECT_DOUBLE_EQ(b.max_y, std::max(corners[2].y(), corners[3].y()));
  // Distorting the undistorted top-left corner again gives back the image corner.
  const Vec2 n = camera.normalize(corners[0]);
  const cv::Mat k = (cv::Mat_<double>(3, 3) << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  const cv::Mat dist = (cv::Mat_<double>(1, 5) << camera.distortion.k1, camera.distortion.k2, camera.distortion.p1,
                        camera.distortion.p2, camera.distortion.k3);
  std::vector<cv::Point2d> back;
  cv::projectPoints(std::vector<cv::Point3d>{{n.x(), n.y(), 1.0}}, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), k, dist,
                    back);
  EXPECT_NEAR(back[0].x, 0.0, 0.5);
  EXPECT_NEAR(back[0].y, 0.0, 0.5);
  EXPECT_TRUE(b.contains(Vec2(camera.cx, camera.cy)));
  EXPECT_FALSE(b.contains(Vec2(b.max_x + 1.0, camera.cy)));
}

TEST(PinholeCamera, IsInImage) {
  const PinholeCamera camera = ideal();
  EXPECT_TRUE(camera.is_in_image(Vec2(0, 0)));
  EXPECT_TRUE(camera.is_in_image(Vec2(639.9, 479.9)));
  EXPECT_FALSE(camera.is_in_image(Vec2(640, 10)));
  EXPECT_FALSE(camera.is_in_image(Vec2(10, -0.1)));
}

TEST(PinholeCamera, CheckNamesBadValue) {
  PinholeCamera camera = ideal();
  EXPECT_NO_THROW(camera.check());
  camera.fx = -1.0;
  try {
    camera.check();
    FAIL() << "expected InputError";
  } catch (const crowdslam::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("Camera.fx"), std::string::npos) << e.what();
  }
  camera = ideal();
  camera.height = 0;
  EXPECT_THROW(camera.check(), crowdslam::InputError);
  camera = ideal();
  camera.bf = -3.0;
  EXPECT_THROW(camera.check(), crowdslam::InputError);
}
