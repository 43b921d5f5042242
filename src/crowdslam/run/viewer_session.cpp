#include "crowdslam/run/viewer_session.h"

#include <spdlog/spdlog.h>

#include <iostream>

#include "crowdslam/util/interrupt.h"

namespace crowdslam::run {

ViewerSession::ViewerSession(const ViewerSessionOptions& options) {
  viewer::ViewerObserverOptions observer_options;
  observer_options.ground_truth = options.ground_truth;
  observer_options.monocular = options.monocular;
  observer_ = std::make_unique<viewer::ViewerObserver>(stream_, &control_, observer_options);
  viewer::ViewerServerOptions server_options;
  server_options.host = options.host;
  server_options.port = options.port;
  server_ = std::make_unique<viewer::ViewerServer>(server_options, stream_, &control_, [this] {
    return std::string("{\"frames\":") + std::to_string(frames_.load()) + ",\"paused\":" +
           (control_.paused() ? "true" : "false") + ",\"finished\":" + (finished_ ? "true" : "false") + "}";
  });
  server_->start();
  pause_timeout_s_ = options.pause_timeout_s;
  // A result, not a log line: printed whatever the log level (--quiet hides info).
  std::cerr << "viewer: " << server_->url() << " (unauthenticated; bound to " << options.host << ")" << std::endl;
  if (!is_loopback_host(options.host)) {
    spdlog::warn("viewer: listening on {}, not a loopback address: anyone who can reach it can watch and pause "
                 "this run (no authentication)",
                 options.host);
  }
}

bool is_loopback_host(const std::string& host) {
  return host == "localhost" || host == "::1" || host == "[::1]" || host.rfind("127.", 0) == 0;
}

ViewerSession::~ViewerSession() { stop(); }

std::chrono::steady_clock::duration ViewerSession::wait_while_paused() {
  const auto timeout = std::chrono::milliseconds(static_cast<long long>(pause_timeout_s_ * 1000.0));
  const auto wait = control_.wait_while_paused([] { return interrupted(); }, [this] { return stream_.clients(); },
                                               timeout);
  if (wait.idle_resumed) {
    spdlog::warn("viewer: the run was paused with no viewer connected for {} s; resuming (--viewer-pause-timeout)",
                 pause_timeout_s_);
  }
  return wait.paused;
}

void ViewerSession::set_progress(size_t frames, bool finished) {
  frames_ = frames;
  finished_ = finished;
}

void ViewerSession::stop() {
  // The observer stays alive (System may still hold it) but takes nothing more.
  finished_ = true;
  observer_->stop();  // publishes what is queued (the final map, "finish")
  server_->stop();
}

}  // namespace crowdslam::run
