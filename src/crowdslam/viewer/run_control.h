#pragma once
// Pause / step / resume of a run from the viewer: the run loop calls wait_while_paused() before each
// frame; the viewer's buttons (HTTP POST /control/...) call pause(), step() and resume(). Thread-safe.
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <mutex>

namespace crowdslam::viewer {

class RunControl {
 public:
  using Clock = std::chrono::steady_clock;

  void pause();
  void resume();
  // While paused: lets exactly one more frame through, then stays paused.
  void step();
  [[nodiscard]] bool paused() const;

  struct Wait {
    Clock::duration paused{0};  // how long it blocked (a paced replay shifts its clock by this much)
    bool idle_resumed = false;  // resumed because no client was connected for the idle timeout
  };
  // Returns at once when running; while paused blocks until resume() or step(), until `stop()` returns
  // true (polled every 100 ms, e.g. an interrupt signal), or, with an `idle_timeout` above zero, until
  // `clients()` has returned 0 for that long: a pause whose viewer went away resumes (the run is not
  // frozen for ever by a page that was closed).
  Wait wait_while_paused(const std::function<bool()>& stop, const std::function<size_t()>& clients = {},
                         std::chrono::milliseconds idle_timeout = std::chrono::milliseconds(0));

 private:
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  bool paused_ = false;
  size_t steps_ = 0;
};

}  // namespace crowdslam::viewer
