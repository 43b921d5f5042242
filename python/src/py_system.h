#pragma once
// The Python System: a crowdslam::system::System with the argument checks, locking and lifetime rules
// Python callers need (docs/PYTHON.md "Threads").
//
// Locking: System itself is meant for one thread. Every call here takes `mutex_`, after releasing the
// GIL (never the other way round: a thread holding the GIL while waiting for the mutex would block the
// tracking thread that needs the GIL back to return). So track() in one Python thread and map_points()
// in another are safe; map_points() then waits for the frame being tracked. The SLAM threads (local
// mapping, loop closing, detector) never touch Python.
//
// Lifetime: shutdown() (also close() and `with`) lets local mapping and loop closing finish their queues
// and stops them; the results stay readable. Destroying an open System (garbage collection) or the
// interpreter exiting (an atexit hook, stop_all()) stops the threads at once instead (stop_now()).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <atomic>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "crowdslam/system/system.h"

namespace crowdslam::python {

namespace py = pybind11;

// What track() returns: the System's FrameReport and the pose at tracking time.
struct FrameResult {
  system::FrameReport report;
  std::optional<geometry::SE3> world_from_cam;
};

struct SystemArgs {
  io::Settings settings;
  system::SystemOptions options;
};

class PySystem {
 public:
  explicit PySystem(SystemArgs args);
  ~PySystem();
  PySystem(const PySystem&) = delete;
  PySystem& operator=(const PySystem&) = delete;

  FrameResult track(const py::object& image, const py::object& depth, const py::object& right, double timestamp_s);
  void shutdown();
  [[nodiscard]] bool closed() const { return closed_.load(); }

  py::array trajectory();
  py::array keyframe_trajectory();
  void save_trajectory(const std::string& path, const std::string& format, bool keyframes);
  py::tuple map_points();
  py::tuple keyframes();
  py::dict load_map(const std::string& path, bool localization);
  void save_map(const std::string& path, const std::string& dataset);
  py::dict stats();

  [[nodiscard]] const io::Settings& settings() const { return args_.settings; }
  [[nodiscard]] const system::SystemOptions& options() const { return args_.options; }

  // The atexit hook: stops the threads of every System still open, at once.
  static void stop_all();

 private:
  class PoseObserver : public system::RunObserver {
   public:
    void on_frame(const system::FrameReport& /*report*/, const std::optional<geometry::SE3>& world_from_cam,
                  const io::FrameImages& /*images*/) override {
      last_pose = world_from_cam;
    }
    std::optional<geometry::SE3> last_pose;
  };

  // The System, or a RuntimeError naming `call` when it was destroyed (interpreter exit).
  system::System& live(const char* call);
  void check_frame(const char* call, const cv::Mat& image, const cv::Mat& depth, const cv::Mat& right);
  // Stops the threads at once and destroys the System (GIL held; the SLAM threads never need it).
  void stop_and_destroy();

  SystemArgs args_;
  std::mutex mutex_;  // one System call at a time (see the header comment)
  std::unique_ptr<system::System> system_;
  PoseObserver observer_;
  std::atomic<bool> closed_{false};  // shutdown() was called: track() refuses, the results stay
  std::optional<cv::Size> first_size_;
  // Of the last frame tracked (NaN: none yet); a timestamp not after it is warned about (RuntimeWarning).
  std::atomic<double> last_timestamp_s_{std::numeric_limits<double>::quiet_NaN()};
};

// Registers System, FrameResult and the module-level stop_all() on `m`.
void bind_system(py::module_& m);

}  // namespace crowdslam::python
