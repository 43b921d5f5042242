#include "crowdslam/run/viewer_session.h"

#include <spdlog/spdlog.h>

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
  spdlog::info("viewer: {} (unauthenticated; bound to {})", server_->url(), options.host);
}

ViewerSession::~ViewerSession() { stop(); }

void ViewerSession::wait_while_paused() {
  control_.wait_while_paused([] { return interrupted(); });
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
