#pragma once
// The live viewer of a run (--viewer): server, event stream, pause control and the observer, started
// before the first frame (a port in use fails the run before it starts) and stopped after the last.
#include <chrono>
#include <memory>
#include <string>

#include "crowdslam/io/trajectory.h"
#include "crowdslam/system/system.h"
#include "crowdslam/viewer/event_stream.h"
#include "crowdslam/viewer/run_control.h"
#include "crowdslam/viewer/viewer_observer.h"
#include "crowdslam/viewer/viewer_server.h"

namespace crowdslam::run {

struct ViewerSessionOptions {
  std::string host = "127.0.0.1";
  int port = 8080;
  io::Trajectory ground_truth;
  bool monocular = false;
  // A pause with no page connected for this long resumes the run (0: never; --viewer-pause-timeout).
  double pause_timeout_s = 60;
};

class ViewerSession {
 public:
  // Starts the server (InputError: port in use, three.js missing) and prints the URL on stderr, also
  // with --quiet (it is a result: with port 0 the only way to learn the port); warns when the host is
  // not a loopback address (anyone who reaches it can pause the run).
  explicit ViewerSession(const ViewerSessionOptions& options);
  ~ViewerSession();
  ViewerSession(const ViewerSession&) = delete;
  ViewerSession& operator=(const ViewerSession&) = delete;

  system::RunObserver& observer() { return *observer_; }
  // Before each frame: blocks while the viewer has paused the run (returns on an interrupt signal, or
  // after the pause timeout with no page connected, with a warning); returns how long it blocked.
  std::chrono::steady_clock::duration wait_while_paused();
  // Frames the run has processed (GET /state) and whether it ended.
  void set_progress(size_t frames, bool finished);
  // Publishes what is left and stops the server (the page shows the end state).
  void stop();
  [[nodiscard]] size_t dropped_updates() const { return observer_->dropped(); }
  [[nodiscard]] std::string url() const { return server_->url(); }

 private:
  viewer::EventStream stream_;
  viewer::RunControl control_;
  std::unique_ptr<viewer::ViewerObserver> observer_;
  std::unique_ptr<viewer::ViewerServer> server_;
  std::atomic<size_t> frames_{0};
  std::atomic<bool> finished_{false};
  double pause_timeout_s_ = 60;
};

// Whether `host` is a loopback address or name (127.0.0.0/8, ::1, localhost).
bool is_loopback_host(const std::string& host);

}  // namespace crowdslam::run
