#pragma once
// numpy <-> C++ conversions shared by every binding file.
//
// Images and depth come in without a copy whenever OpenCV can describe the array's layout (pixels
// contiguous within a row, any row stride); other layouts (transposed or flipped views) are copied once
// into a contiguous array. Arrays handed to Python own their buffer (a capsule keeps the cv::Mat or the
// std::vector alive), so nothing is copied on the way out either.
//
// Bad input raises TypeError (not an array, wrong dtype) or ValueError (wrong shape, size or values);
// every message starts with the argument's name (`what`, e.g. "track(): image") and says what was
// expected and what was given.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "crowdslam/geometry/se3.h"
#include "crowdslam/io/trajectory.h"
#include "crowdslam/people/detector.h"

namespace crowdslam::python {

namespace py = pybind11;

// "uint16 array of shape (480, 640)", "list", "None": what the caller gave, for error messages.
std::string describe(const py::handle& object);

// An image as cv::Mat over the array's memory. `keep` receives the array that owns that memory (the
// argument itself, or the contiguous copy); the Mat is valid while `keep` lives.
//   colour_or_grey: uint8 (H, W, 3) BGR or (H, W) grey ((H, W, 1) is taken as grey too).
cv::Mat image_from_array(const py::handle& object, const std::string& what, py::object& keep);
// Depth for RGB-D: uint16 (H, W) raw sensor units (used as is), or float32 (H, W) metres, converted to raw
// units with `depth_map_factor` (NaN, inf and values <= 0 become 0 = no depth; clipped at 65535).
cv::Mat depth_from_array(const py::handle& object, const std::string& what, double depth_map_factor,
                         py::object& keep);

// A cv::Mat as a numpy array sharing its (reference-counted) buffer.
py::array mat_to_array(const cv::Mat& mat);

// A vector as a numpy array of `shape` that takes over its buffer.
template <typename T>
py::array_t<T> vector_to_array(std::vector<T>&& values, const std::vector<py::ssize_t>& shape) {
  auto* owned = new std::vector<T>(std::move(values));
  py::capsule owner(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>(shape, owned->data(), owner);
}

// 4x4 float64 homogeneous matrix.
py::array_t<double> pose_to_array(const geometry::SE3& pose);
py::object optional_pose_to_array(const std::optional<geometry::SE3>& pose);

// N x 8 float64 TUM rows: timestamp tx ty tz qx qy qz qw (the order of the TUM files we write).
py::array_t<double> trajectory_to_array(const io::Trajectory& trajectory);
// The inverse; `what` names the argument. Quaternions are normalised, as the file readers do; zero or
// non-finite quaternions and non-finite values are a ValueError naming the row.
io::Trajectory trajectory_from_array(const py::handle& object, const std::string& what);

// Person boxes as N x 4 float32 (x, y, width, height) pixels, and their N float32 confidences.
py::array_t<float> boxes_to_array(const std::vector<people::PersonBox>& boxes);
py::array_t<float> box_scores(const std::vector<people::PersonBox>& boxes);
// Keypoint positions as N x 2 float32 (x, y) pixels.
py::array_t<float> keypoints_to_array(const std::vector<cv::KeyPoint>& keys);

}  // namespace crowdslam::python
