#include "py_arrays.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>

namespace crowdslam::python {

namespace {

std::string shape_text(const py::array& array) {
  std::ostringstream out;
  out << "(";
  for (py::ssize_t i = 0; i < array.ndim(); ++i) out << (i ? ", " : "") << array.shape(i);
  out << (array.ndim() == 1 ? ",)" : ")");
  return out.str();
}

std::string dtype_name(const py::array& array) { return py::str(array.dtype()).cast<std::string>(); }

py::array as_array(const py::handle& object, const std::string& what, const std::string& expected) {
  if (!py::isinstance<py::array>(object)) {
    throw py::type_error(what + ": expected a numpy array (" + expected + "), got " + describe(object));
  }
  return py::reinterpret_borrow<py::array>(object);
}

// dtype checks use py::isinstance<py::array_t<T>>: numpy's equivalence test, so a dtype object that is
// equal but not the cached one (from a view or a buffer) is accepted too.

// True when OpenCV can describe the array as rows of contiguous pixels (row stride positive and a
// multiple of the element size; for an (H, W, C) array, channels and pixels packed).
bool opencv_layout(const py::array& array) {
  const auto item = array.itemsize();
  const auto channels = array.ndim() == 3 ? array.shape(2) : 1;
  if (array.ndim() == 3 && array.strides(2) != item) return false;
  if (array.strides(1) != item * channels) return false;
  return array.strides(0) >= item * channels * array.shape(1) && array.strides(0) % item == 0;
}

// The array itself when OpenCV can use its layout, else a C-contiguous copy.
py::array opencv_compatible(const py::array& array) {
  if (opencv_layout(array)) return array;
  return py::module_::import("numpy").attr("ascontiguousarray")(array).cast<py::array>();
}

cv::Mat wrap(const py::array& array, int type) {
  // cv::Mat takes a non-const pointer; images are only read (track, detect never write into them).
  auto* data = const_cast<void*>(array.data());
  return cv::Mat(static_cast<int>(array.shape(0)), static_cast<int>(array.shape(1)), type, data,
                 static_cast<size_t>(array.strides(0)));
}

void check_not_empty(const py::array& array, const std::string& what) {
  if (array.shape(0) == 0 || array.shape(1) == 0) {
    throw py::value_error(what + ": empty image of shape " + shape_text(array));
  }
  if (array.shape(0) > (1 << 20) || array.shape(1) > (1 << 20)) {
    throw py::value_error(what + ": image of shape " + shape_text(array) + " is too large");
  }
}

}  // namespace

std::string describe(const py::handle& object) {
  if (object.is_none()) return "None";
  if (py::isinstance<py::array>(object)) {
    const auto array = py::reinterpret_borrow<py::array>(object);
    return dtype_name(array) + " array of shape " + shape_text(array);
  }
  return py::str(py::type::handle_of(object).attr("__name__")).cast<std::string>();
}

cv::Mat image_from_array(const py::handle& object, const std::string& what, py::object& keep) {
  const char* expected = "uint8, shape (H, W, 3) BGR or (H, W) grey";
  py::array array = as_array(object, what, expected);
  if (!py::isinstance<py::array_t<uint8_t>>(array)) {
    throw py::type_error(what + ": expected " + std::string(expected) + ", got " + describe(array));
  }
  const bool grey = array.ndim() == 2 || (array.ndim() == 3 && array.shape(2) == 1);
  const bool colour = array.ndim() == 3 && array.shape(2) == 3;
  if (!grey && !colour) {
    throw py::value_error(what + ": expected " + std::string(expected) + ", got " + describe(array));
  }
  check_not_empty(array, what);
  array = opencv_compatible(array);
  keep = array;
  return wrap(array, colour ? CV_8UC3 : CV_8UC1);
}

cv::Mat depth_from_array(const py::handle& object, const std::string& what, double depth_map_factor,
                         py::object& keep) {
  const char* expected = "uint16 (H, W) raw sensor units or float32 (H, W) metres";
  py::array array = as_array(object, what, expected);
  const bool u16 = py::isinstance<py::array_t<uint16_t>>(array);
  const bool f32 = py::isinstance<py::array_t<float>>(array);
  if (!u16 && !f32) throw py::type_error(what + ": expected " + std::string(expected) + ", got " + describe(array));
  if (array.ndim() != 2 && !(array.ndim() == 3 && array.shape(2) == 1)) {
    throw py::value_error(what + ": expected " + std::string(expected) + ", got " + describe(array));
  }
  check_not_empty(array, what);
  array = opencv_compatible(array);
  keep = array;
  if (u16) return wrap(array, CV_16UC1);
  // Metres to the raw units the system expects (the same quantisation a 16-bit sensor has).
  const cv::Mat metres = wrap(array, CV_32FC1);
  cv::Mat raw(metres.size(), CV_16UC1);
  for (int r = 0; r < metres.rows; ++r) {
    const float* in = metres.ptr<float>(r);
    uint16_t* out = raw.ptr<uint16_t>(r);
    for (int c = 0; c < metres.cols; ++c) {
      const double value = static_cast<double>(in[c]) * depth_map_factor;
      out[c] = std::isfinite(value) && value > 0 ? static_cast<uint16_t>(std::min(65535.0, std::round(value))) : 0;
    }
  }
  return raw;
}

py::array mat_to_array(const cv::Mat& mat) {
  if (mat.empty()) return py::array();
  py::dtype dtype;
  switch (mat.depth()) {
    case CV_8U:
      dtype = py::dtype::of<uint8_t>();
      break;
    case CV_16U:
      dtype = py::dtype::of<uint16_t>();
      break;
    case CV_32F:
      dtype = py::dtype::of<float>();
      break;
    default:
      throw std::logic_error("mat_to_array: unsupported cv::Mat depth " + std::to_string(mat.depth()));
  }
  auto* owned = new cv::Mat(mat);  // shares the reference-counted buffer
  py::capsule owner(owned, [](void* p) { delete static_cast<cv::Mat*>(p); });
  const auto elem1 = static_cast<py::ssize_t>(mat.elemSize1());
  std::vector<py::ssize_t> shape{mat.rows, mat.cols};
  std::vector<py::ssize_t> strides{static_cast<py::ssize_t>(mat.step[0]), static_cast<py::ssize_t>(mat.elemSize())};
  if (mat.channels() > 1) {
    shape.push_back(mat.channels());
    strides.push_back(elem1);
  }
  return py::array(dtype, shape, strides, owned->data, owner);
}

py::array_t<double> pose_to_array(const geometry::SE3& pose) {
  const geometry::Mat4 m = pose.matrix();
  std::vector<double> values(16);
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) values[static_cast<size_t>(4 * r + c)] = m(r, c);
  }
  return vector_to_array(std::move(values), {4, 4});
}

py::object optional_pose_to_array(const std::optional<geometry::SE3>& pose) {
  if (!pose) return py::none();
  return pose_to_array(*pose);
}

py::array_t<double> trajectory_to_array(const io::Trajectory& trajectory) {
  std::vector<double> values;
  values.reserve(trajectory.size() * 8);
  for (const auto& pose : trajectory) {
    const geometry::Vec3& t = pose.world_from_cam.translation();
    // As the TUM writer: the stored unit quaternion, normalised again.
    const Eigen::Quaterniond q = pose.world_from_cam.rotation().normalized();
    for (double v : {pose.timestamp_s, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()}) values.push_back(v);
  }
  return vector_to_array(std::move(values), {static_cast<py::ssize_t>(trajectory.size()), 8});
}

io::Trajectory trajectory_from_array(const py::handle& object, const std::string& what) {
  const char* expected = "float64, shape (N, 8): timestamp tx ty tz qx qy qz qw";
  const py::array array = as_array(object, what, expected);
  if (!py::isinstance<py::array_t<double>>(array) && !py::isinstance<py::array_t<float>>(array)) {
    throw py::type_error(what + ": expected " + std::string(expected) + ", got " + describe(array));
  }
  if (array.ndim() != 2 || array.shape(1) != 8) {
    throw py::value_error(what + ": expected " + std::string(expected) + ", got " + describe(array));
  }
  const auto values = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array);
  const auto rows = values.unchecked<2>();
  io::Trajectory trajectory;
  trajectory.reserve(static_cast<size_t>(rows.shape(0)));
  for (py::ssize_t i = 0; i < rows.shape(0); ++i) {
    for (py::ssize_t k = 0; k < 8; ++k) {
      if (!std::isfinite(rows(i, k))) {
        throw py::value_error(what + ": row " + std::to_string(i) + " has a non-finite value in column " +
                              std::to_string(k));
      }
    }
    // As read_tum_trajectory: normalised, then SE3 normalises once more (bit-identical poses).
    const Eigen::Quaterniond q(rows(i, 7), rows(i, 4), rows(i, 5), rows(i, 6));
    if (!(q.norm() > 1e-12)) throw py::value_error(what + ": row " + std::to_string(i) + ": zero quaternion");
    trajectory.push_back({rows(i, 0), geometry::SE3(q.normalized(), geometry::Vec3(rows(i, 1), rows(i, 2), rows(i, 3)))});
  }
  return trajectory;
}

py::array_t<float> boxes_to_array(const std::vector<people::PersonBox>& boxes) {
  std::vector<float> values;
  values.reserve(boxes.size() * 4);
  for (const auto& b : boxes) values.insert(values.end(), {b.box.x, b.box.y, b.box.width, b.box.height});
  return vector_to_array(std::move(values), {static_cast<py::ssize_t>(boxes.size()), 4});
}

py::array_t<float> box_scores(const std::vector<people::PersonBox>& boxes) {
  std::vector<float> values;
  values.reserve(boxes.size());
  for (const auto& b : boxes) values.push_back(b.confidence);
  return vector_to_array(std::move(values), {static_cast<py::ssize_t>(boxes.size())});
}

py::array_t<float> keypoints_to_array(const std::vector<cv::KeyPoint>& keys) {
  std::vector<float> values;
  values.reserve(keys.size() * 2);
  for (const auto& k : keys) values.insert(values.end(), {k.pt.x, k.pt.y});
  return vector_to_array(std::move(values), {static_cast<py::ssize_t>(keys.size()), 2});
}

}  // namespace crowdslam::python
