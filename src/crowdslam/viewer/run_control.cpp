#include "crowdslam/viewer/run_control.h"

#include <chrono>

namespace crowdslam::viewer {

void RunControl::pause() {
  std::lock_guard lock(mutex_);
  paused_ = true;
  steps_ = 0;
}

void RunControl::resume() {
  {
    std::lock_guard lock(mutex_);
    paused_ = false;
  }
  cv_.notify_all();
}

void RunControl::step() {
  {
    std::lock_guard lock(mutex_);
    if (paused_) ++steps_;
  }
  cv_.notify_all();
}

bool RunControl::paused() const {
  std::lock_guard lock(mutex_);
  return paused_;
}

void RunControl::wait_while_paused(const std::function<bool()>& stop) {
  std::unique_lock lock(mutex_);
  while (paused_ && steps_ == 0) {
    if (stop && stop()) return;
    cv_.wait_for(lock, std::chrono::milliseconds(100));
  }
  if (paused_ && steps_ > 0) --steps_;
}

}  // namespace crowdslam::viewer
