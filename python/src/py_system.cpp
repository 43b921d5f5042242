// crowdslam.System: tracking from Python (py_system.h for the locking and lifetime rules).
#include "py_system.h"

#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>
#include <set>

#include "crowdslam/mapdb/map_target.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"
#include "crowdslam/util/version.h"
#include "py_arrays.h"
#include "py_gil.h"

namespace crowdslam::python {

namespace {

// Every open PySystem, for the atexit hook. Only touched with the GIL held (constructor, destructor and
// stop_all all run with it), which is what serialises it.
std::set<PySystem*>& registry() {
  static std::set<PySystem*> systems;
  return systems;
}

std::string size_text(cv::Size size) { return std::to_string(size.width) + "x" + std::to_string(size.height); }

}  // namespace

PySystem::PySystem(SystemArgs args) : args_(std::move(args)) {
  // Loading the vocabulary and the detector takes a while.
  system_ = without_gil([this] { return std::make_unique<system::System>(args_.settings, args_.options); });
  system_->add_observer(&observer_);
  registry().insert(this);
}

PySystem::~PySystem() {
  registry().erase(this);
  stop_and_destroy();
}

void PySystem::stop_and_destroy() {
  std::lock_guard lock(mutex_);
  if (!system_) return;
  // An open System that is collected (or outlives the interpreter) has no one to read its results:
  // stop at once rather than finish the mapping queue.
  if (!closed_) system_->stop_now();
  closed_ = true;
  system_.reset();
}

void PySystem::stop_all() {
  std::vector<py::object> open;  // the Python objects keep the PySystems alive while the GIL is released
  for (PySystem* s : registry()) open.push_back(py::cast(s, py::return_value_policy::reference));
  for (auto& object : open) {
    auto& s = object.cast<PySystem&>();
    without_gil([&s] { s.stop_and_destroy(); });  // a daemon thread may still be in track(): wait for its frame
  }
}

system::System& PySystem::live(const char* call) {
  if (!system_) {
    throw std::runtime_error(std::string("System.") + call +
                             "(): the System was stopped and destroyed at interpreter exit");
  }
  return *system_;
}

void PySystem::check_frame(const char* call, const cv::Mat& image, const cv::Mat& depth, const cv::Mat& right) {
  const std::string what = std::string(call) + ": ";
  const auto& camera = args_.settings.camera;
  if (camera.width > 0 && camera.height > 0 && (image.cols != camera.width || image.rows != camera.height)) {
    throw py::value_error(what + "image: " + size_text(image.size()) + " pixels, but the settings " +
                          args_.settings.path + " give Camera.width/height " +
                          size_text(cv::Size(camera.width, camera.height)));
  }
  if (first_size_ && image.size() != *first_size_) {
    throw py::value_error(what + "image: " + size_text(image.size()) + " pixels, but the first frame was " +
                          size_text(*first_size_));
  }
  if (!depth.empty() && depth.size() != image.size()) {
    throw py::value_error(what + "depth: " + size_text(depth.size()) + " pixels, but the image is " +
                          size_text(image.size()) + " (they must be registered, the same size)");
  }
  if (!right.empty() && right.size() != image.size()) {
    throw py::value_error(what + "right: " + size_text(right.size()) + " pixels, but the image is " +
                          size_text(image.size()));
  }
  if (!first_size_) first_size_ = image.size();
}

FrameResult PySystem::track(const py::object& image, const py::object& depth, const py::object& right,
                            double timestamp_s) {
  const char* call = "track()";
  if (!std::isfinite(timestamp_s)) {
    throw py::value_error("track(): timestamp: expected a finite time in seconds, got " + std::to_string(timestamp_s));
  }
  if (const double last = last_timestamp_s_.load(); !std::isnan(last) && timestamp_s <= last) {
    // Accepted (frames are taken in the order given), but never silently: motion and pacing assume time
    // goes forward.
    const std::string message = "track(): timestamp " + std::to_string(timestamp_s) +
                                " is not after the previous frame's (" + std::to_string(last) + ")";
    if (PyErr_WarnEx(PyExc_RuntimeWarning, message.c_str(), 1) != 0) throw py::error_already_set();
  }
  const io::SensorKind sensor = args_.options.sensor;
  const std::string sensor_name = io::to_string(sensor);
  py::object keep_image, keep_depth, keep_right;  // own the memory the cv::Mats point into
  io::FrameImages images;
  images.colour = image_from_array(image, "track(): image", keep_image);
  if (sensor == io::SensorKind::kRgbd) {
    if (depth.is_none()) {
      throw py::value_error("track(): depth: the System's sensor is rgbd, which needs a depth image (uint16 raw "
                            "units or float32 metres, (H, W)), got None");
    }
    images.depth = depth_from_array(depth, "track(): depth", args_.settings.depth_map_factor, keep_depth);
  } else if (!depth.is_none()) {
    throw py::value_error("track(): depth: given, but the System's sensor is " + sensor_name +
                          " (depth is for sensor=\"rgbd\")");
  }
  if (sensor == io::SensorKind::kStereo) {
    if (right.is_none()) {
      throw py::value_error("track(): right: the System's sensor is stereo, which needs the right image, got None");
    }
    images.right = image_from_array(right, "track(): right", keep_right);
  } else if (!right.is_none()) {
    throw py::value_error("track(): right: given, but the System's sensor is " + sensor_name +
                          " (right is for sensor=\"stereo\")");
  }
  return without_gil([&] {
    std::lock_guard lock(mutex_);
    system::System& slam = live("track");
    if (closed_) {
      throw std::runtime_error("System.track(): the System is closed (shutdown(), close() or the end of its `with` "
                               "block); create a new System to track more frames");
    }
    check_frame(call, images.colour, images.depth, images.right);
    FrameResult result;
    result.report = slam.track(images, timestamp_s);
    last_timestamp_s_.store(timestamp_s);
    result.world_from_cam = observer_.last_pose;
    return result;
  });
}

void PySystem::shutdown() {
  without_gil([this] {  // local mapping may still have keyframes queued
    std::lock_guard lock(mutex_);
    if (closed_ || !system_) return;
    system_->shutdown();
    closed_ = true;
  });
}

py::array PySystem::trajectory() {
  const io::Trajectory trajectory = without_gil([this] {
    std::lock_guard lock(mutex_);
    return live("trajectory").camera_trajectory();
  });
  return trajectory_to_array(trajectory);
}

py::array PySystem::keyframe_trajectory() {
  const io::Trajectory trajectory = without_gil([this] {
    std::lock_guard lock(mutex_);
    return live("keyframe_trajectory").keyframe_trajectory();
  });
  return trajectory_to_array(trajectory);
}

void PySystem::save_trajectory(const std::string& path, const std::string& format, bool keyframes) {
  const std::string name = format.empty() ? args_.settings.output.trajectory_format : format;
  if (name != "tum" && name != "kitti" && name != "euroc") {
    throw py::value_error("save_trajectory(): format: expected 'tum', 'kitti' or 'euroc', got '" + name + "'");
  }
  without_gil([&] {
    std::lock_guard lock(mutex_);
    system::System& slam = live("save_trajectory");
    io::write_trajectory(path, keyframes ? slam.keyframe_trajectory() : slam.camera_trajectory(),
                         io::parse_trajectory_format(name));
  });
}

py::tuple PySystem::map_points() {
  const auto snapshot = without_gil([this] {
    std::lock_guard lock(mutex_);
    return live("map_points").map_snapshot();
  });
  const auto n = snapshot->points.size();
  std::vector<float> positions;
  std::vector<int32_t> observations;
  std::vector<uint64_t> ids;
  positions.reserve(3 * n);
  observations.reserve(n);
  ids.reserve(n);
  for (const auto& p : snapshot->points) {
    positions.insert(positions.end(), {p.x, p.y, p.z});
    observations.push_back(p.observations);
    ids.push_back(p.id);
  }
  const auto rows = static_cast<py::ssize_t>(n);
  return py::make_tuple(vector_to_array(std::move(positions), {rows, 3}),
                        vector_to_array(std::move(observations), {rows}), vector_to_array(std::move(ids), {rows}));
}

py::tuple PySystem::keyframes() {
  const auto snapshot = without_gil([this] {
    std::lock_guard lock(mutex_);
    return live("keyframes").map_snapshot();
  });
  const auto n = snapshot->keyframes.size();
  std::vector<uint64_t> ids;
  std::vector<double> stamps;
  std::vector<double> poses;
  poses.reserve(16 * n);
  for (const auto& kf : snapshot->keyframes) {
    ids.push_back(kf.id);
    stamps.push_back(kf.timestamp_s);
    const geometry::Mat4 m = kf.world_from_cam.matrix();
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) poses.push_back(m(r, c));
    }
  }
  const auto rows = static_cast<py::ssize_t>(n);
  return py::make_tuple(vector_to_array(std::move(ids), {rows}), vector_to_array(std::move(stamps), {rows}),
                        vector_to_array(std::move(poses), {rows, 4, 4}));
}

py::dict PySystem::load_map(const std::string& path, bool localization) {
  const mapdb::LoadedMap loaded = without_gil([&] {
    std::lock_guard lock(mutex_);
    if (closed_) throw std::runtime_error("System.load_map(): the System is closed");
    return live("load_map").load_map(path, localization);
  });
  py::dict origin;
  origin["dataset"] = loaded.header.origin.dataset;
  origin["created_utc"] = loaded.header.origin.created_utc;
  origin["crowdslam_version"] = loaded.header.origin.crowdslam_version;
  origin["end_state"] = loaded.header.origin.end_state;
  py::dict info;
  info["path"] = path;
  info["mode"] = localization ? "localization" : "continue_mapping";
  info["keyframes"] = loaded.keyframes.size();
  info["map_points"] = loaded.map_points;
  info["origin"] = origin;
  return info;
}

void PySystem::save_map(const std::string& path, const std::string& dataset) {
  without_gil([&] {
    std::lock_guard lock(mutex_);
    system::System& slam = live("save_map");
    if (!closed_ && !args_.options.sequential) {
      // System::save_map needs a map nobody writes: in threaded mode local mapping and loop closing do.
      throw std::runtime_error("System.save_map(): local mapping and loop closing are still running; call "
                               "shutdown() first (or track with sequential=True)");
    }
    mapdb::MapOrigin origin;
    origin.dataset = dataset;
    origin.created_utc = utc_now();
    origin.crowdslam_version = crowdslam::version();
    origin.end_state = closed_ ? "completed" : "running";
    // As the CLI's --save-map with --overwrite: a new file or a crowdslam map, never anything else.
    mapdb::check_map_target(path, true, "save_map(): path");
    slam.save_map(path, origin);
  });
}

py::dict PySystem::stats() {
  py::dict out;
  size_t tracked = 0, keyframes = 0, points = 0;
  int resets = 0;
  size_t loops = 0;
  std::string detector;
  std::vector<system::MapSegment> segments;
  without_gil([&] {
    std::lock_guard lock(mutex_);
    system::System& slam = live("stats");
    tracked = slam.tracked_frames();
    keyframes = slam.num_keyframes();
    points = slam.num_map_points();
    resets = slam.map_resets();
    loops = slam.loop_stats().loops.size();
    detector = slam.detector_name();
    segments = slam.segments();
  });
  out["tracked_frames"] = tracked;
  out["keyframes"] = keyframes;
  out["map_points"] = points;
  out["map_resets"] = resets;
  out["loops_closed"] = loops;
  out["detector"] = detector;
  py::list segment_list;
  for (const auto& s : segments) {
    py::dict d;
    d["map_id"] = s.map_id;
    d["first_frame"] = s.first_frame;
    d["last_frame"] = s.last_frame;
    d["frames"] = s.frames;
    d["tracked"] = s.tracked;
    d["keyframes"] = s.keyframes;
    segment_list.append(d);
  }
  out["segments"] = segment_list;
  return out;
}

}  // namespace crowdslam::python
