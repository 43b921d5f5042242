#pragma once
// Pinhole camera with radial-tangential (OpenCV "plumb bob") distortion.
//
// Keypoints are undistorted once after extraction (undistort_points); everything downstream
// (matching, triangulation, optimisation) works on undistorted pixels with the plain pinhole
// model in project()/unproject(). Stereo and RGB-D use a virtual right camera: bf = baseline * fx,
// right coordinate u_r = u - bf / depth. bf = 0 means monocular.
#include <Eigen/Core>
#include <opencv2/core/types.hpp>
#include <vector>

#include "crowdslam/geometry/se3.h"

namespace crowdslam::geometry {

using Vec2 = Eigen::Vector2d;

// Axis-aligned pixel rectangle [min_x, max_x) x [min_y, max_y).
struct ImageBounds {
  double min_x = 0.0;
  double max_x = 0.0;
  double min_y = 0.0;
  double max_y = 0.0;

  [[nodiscard]] bool contains(const Vec2& pixel) const {
    return pixel.x() >= min_x && pixel.x() < max_x && pixel.y() >= min_y && pixel.y() < max_y;
  }
  [[nodiscard]] double width() const { return max_x - min_x; }
  [[nodiscard]] double height() const { return max_y - min_y; }
};

// OpenCV order k1, k2, p1, p2, k3.
struct Distortion {
  double k1 = 0.0;
  double k2 = 0.0;
  double p1 = 0.0;
  double p2 = 0.0;
  double k3 = 0.0;

  [[nodiscard]] bool is_zero() const { return k1 == 0.0 && k2 == 0.0 && p1 == 0.0 && p2 == 0.0 && k3 == 0.0; }
};

struct PinholeCamera {
  double fx = 0.0;
  double fy = 0.0;
  double cx = 0.0;
  double cy = 0.0;
  Distortion distortion;
  int width = 0;
  int height = 0;
  double bf = 0.0;  // baseline (m) * fx; 0 for monocular

  // Throws InputError naming the bad value ("Camera.fx must be > 0, got -1").
  void check() const;

  [[nodiscard]] bool is_stereo() const { return bf > 0.0; }
  [[nodiscard]] double baseline_m() const { return bf / fx; }

  // Undistorted pixel of a point in the camera frame (z > 0 expected; not checked).
  [[nodiscard]] Vec2 project(const Vec3& point_cam) const {
    const double inv_z = 1.0 / point_cam.z();
    return {fx * point_cam.x() * inv_z + cx, fy * point_cam.y() * inv_z + cy};
  }
  // Point in the camera frame at the given depth (z) seen at an undistorted pixel.
  [[nodiscard]] Vec3 unproject(const Vec2& pixel, double depth) const {
    return {(pixel.x() - cx) / fx * depth, (pixel.y() - cy) / fy * depth, depth};
  }
  // Normalised image coordinates (z = 1 plane) of an undistorted pixel.
  [[nodiscard]] Vec2 normalize(const Vec2& pixel) const { return {(pixel.x() - cx) / fx, (pixel.y() - cy) / fy}; }
  // Horizontal coordinate in the virtual right image of a point at the given depth.
  [[nodiscard]] double right_u(double u, double depth) const { return u - bf / depth; }

  [[nodiscard]] Mat3 intrinsic_matrix() const;

  // Inside the raw image [0, width) x [0, height). For undistorted pixels use
  // undistorted_bounds().contains(pixel) (compute the bounds once and keep them).
  [[nodiscard]] bool is_in_image(const Vec2& pixel) const {
    return pixel.x() >= 0.0 && pixel.x() < width && pixel.y() >= 0.0 && pixel.y() < height;
  }

  // Undistorts pixels with cv::undistortPoints (P = K, so the result is in pixels again).
  // Without distortion the input is returned unchanged (no OpenCV call).
  [[nodiscard]] std::vector<cv::Point2f> undistort_points(const std::vector<cv::Point2f>& pixels) const;
  [[nodiscard]] std::vector<Vec2> undistort_points(const std::vector<Vec2>& pixels) const;
  // The raw (distorted) pixel of an undistorted one: the plumb-bob model applied forwards (closed form,
  // the inverse of undistort_points). Without distortion the input is returned unchanged.
  [[nodiscard]] Vec2 distort_pixel(const Vec2& undistorted) const {
    if (distortion.is_zero()) return undistorted;
    const double x = (undistorted.x() - cx) / fx;
    const double y = (undistorted.y() - cy) / fy;
    const double r2 = x * x + y * y;
    const Distortion& d = distortion;
    const double radial = 1.0 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
    const double xd = x * radial + 2.0 * d.p1 * x * y + d.p2 * (r2 + 2.0 * x * x);
    const double yd = y * radial + d.p1 * (r2 + 2.0 * y * y) + 2.0 * d.p2 * x * y;
    return {fx * xd + cx, fy * yd + cy};
  }

  // Bounds of the undistorted image: the four image corners are undistorted and the extreme
  // coordinates taken (left from the left corners, right from the right ones, etc.).
  // Without distortion: [0, width) x [0, height).
  [[nodiscard]] ImageBounds undistorted_bounds() const;
};

}  // namespace crowdslam::geometry
