#include "crowdslam/viewer/run_control.h"

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

RunControl::Wait RunControl::wait_while_paused(const std::function<bool()>& stop,
                                               const std::function<size_t()>& clients,
                                               std::chrono::milliseconds idle_timeout) {
  Wait result;
  const auto start = Clock::now();
  auto last_client = start;  // when a client was last seen connected
  std::unique_lock lock(mutex_);
  while (paused_ && steps_ == 0) {
    if (stop && stop()) break;
    if (idle_timeout.count() > 0 && clients) {
      const auto now = Clock::now();
      lock.unlock();  // clients() takes the stream's lock: never both at once
      const size_t connected = clients();
      lock.lock();
      if (connected > 0) {
        last_client = now;
      } else if (now - last_client >= idle_timeout) {
        paused_ = false;
        result.idle_resumed = true;
        break;
      }
    }
    cv_.wait_for(lock, std::chrono::milliseconds(100));
  }
  if (paused_ && steps_ > 0) --steps_;
  result.paused = Clock::now() - start;
  return result;
}

}  // namespace crowdslam::viewer
