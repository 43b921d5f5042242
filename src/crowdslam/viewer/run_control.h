#pragma once
// Pause / step / resume of a run from the viewer: the run loop calls wait_while_paused() before each
// frame; the viewer's buttons (HTTP POST /control/...) call pause(), step() and resume(). Thread-safe.
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <mutex>

namespace crowdslam::viewer {

class RunControl {
 public:
  void pause();
  void resume();
  // While paused: lets exactly one more frame through, then stays paused.
  void step();
  [[nodiscard]] bool paused() const;
  // Returns at once when running; while paused blocks until resume() or step(), or until `stop()` returns
  // true (polled every 100 ms, e.g. an interrupt signal).
  void wait_while_paused(const std::function<bool()>& stop);

 private:
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  bool paused_ = false;
  size_t steps_ = 0;
};

}  // namespace crowdslam::viewer
