#include "crowdslam/geometry/camera.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <sstream>
#include <string>

#include "crowdslam/util/error.h"

namespace crowdslam::geometry {

namespace {

void require(bool ok, const std::string& key, const std::string& rule, double value) {
  if (ok) return;
  std::ostringstream message;
  message << "Camera." << key << " must be " << rule << ", got " << value;
  throw InputError(message.str());
}

cv::Mat camera_matrix_cv(const PinholeCamera& camera) {
  return (cv::Mat_<double>(3, 3) << camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0);
}

cv::Mat distortion_cv(const Distortion& d) { return (cv::Mat_<double>(1, 5) << d.k1, d.k2, d.p1, d.p2, d.k3); }

}  // namespace

void PinholeCamera::check() const {
  require(std::isfinite(fx) && fx > 0.0, "fx", "> 0", fx);
  require(std::isfinite(fy) && fy > 0.0, "fy", "> 0", fy);
  require(std::isfinite(cx), "cx", "finite", cx);
  require(std::isfinite(cy), "cy", "finite", cy);
  require(width > 0, "width", "> 0", width);
  require(height > 0, "height", "> 0", height);
  require(std::isfinite(bf) && bf >= 0.0, "bf", ">= 0", bf);
  const Distortion& d = distortion;
  require(std::isfinite(d.k1), "k1", "finite", d.k1);
  require(std::isfinite(d.k2), "k2", "finite", d.k2);
  require(std::isfinite(d.p1), "p1", "finite", d.p1);
  require(std::isfinite(d.p2), "p2", "finite", d.p2);
  require(std::isfinite(d.k3), "k3", "finite", d.k3);
}

Mat3 PinholeCamera::intrinsic_matrix() const {
  Mat3 k;
  k << fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0;
  return k;
}

std::vector<cv::Point2f> PinholeCamera::undistort_points(const std::vector<cv::Point2f>& pixels) const {
  if (distortion.is_zero() || pixels.empty()) return pixels;
  const cv::Mat k = camera_matrix_cv(*this);
  std::vector<cv::Point2f> undistorted;
  cv::undistortPoints(pixels, undistorted, k, distortion_cv(distortion), cv::noArray(), k);
  return undistorted;
}

std::vector<Vec2> PinholeCamera::undistort_points(const std::vector<Vec2>& pixels) const {
  if (distortion.is_zero() || pixels.empty()) return pixels;
  // Double precision path: OpenCV accepts CV_64FC2 input.
  cv::Mat input(static_cast<int>(pixels.size()), 1, CV_64FC2);
  for (int i = 0; i < input.rows; ++i) input.at<cv::Vec2d>(i) = cv::Vec2d(pixels[i].x(), pixels[i].y());
  const cv::Mat k = camera_matrix_cv(*this);
  cv::Mat output;
  cv::undistortPoints(input, output, k, distortion_cv(distortion), cv::noArray(), k);
  std::vector<Vec2> undistorted(pixels.size());
  for (int i = 0; i < output.rows; ++i) {
    const cv::Vec2d p = output.at<cv::Vec2d>(i);
    undistorted[i] = Vec2(p[0], p[1]);
  }
  return undistorted;
}

ImageBounds PinholeCamera::undistorted_bounds() const {
  const double w = width;
  const double h = height;
  if (distortion.is_zero()) return ImageBounds{0.0, w, 0.0, h};
  // Corners: top-left, top-right, bottom-left, bottom-right.
  const std::vector<Vec2> c = undistort_points(std::vector<Vec2>{{0.0, 0.0}, {w, 0.0}, {0.0, h}, {w, h}});
  ImageBounds bounds;
  bounds.min_x = std::min(c[0].x(), c[2].x());
  bounds.max_x = std::max(c[1].x(), c[3].x());
  bounds.min_y = std::min(c[0].y(), c[1].y());
  bounds.max_y = std::max(c[2].y(), c[3].y());
  return bounds;
}

}  // namespace crowdslam::geometry
