#pragma once
// --pace sensor: replays a recorded sequence at the rate it was recorded.
//
// Frame k "arrives" at wall time start + (stamp_k - stamp_0). admit(stamp_k) is called when tracking is
// ready for the next frame: it sleeps until the frame has arrived, and returns false (drop it) when the
// frame is stale, i.e. the next frame would already have arrived too (now >= arrival_k + the gap to the
// previous frame). A live camera behaves the same: a frame nobody took is overwritten by the next.
#include <chrono>
#include <cstddef>
#include <optional>

namespace crowdslam::run {

class SensorPacer {
 public:
  using Clock = std::chrono::steady_clock;

  // true: process the frame (after sleeping until its arrival); false: it is stale, drop it.
  bool admit(double stamp_s);
  [[nodiscard]] size_t dropped() const { return dropped_; }
  // The replay was paused for `paused` (the viewer's pause): the sensor's clock stops too, so frames
  // after the pause arrive as late as the pause was long, and none is dropped for it.
  void shift(Clock::duration paused) {
    if (start_) *start_ += paused;
  }

 private:
  std::optional<Clock::time_point> start_;
  double first_stamp_s_ = 0;
  std::optional<double> previous_stamp_s_;
  size_t dropped_ = 0;
};

}  // namespace crowdslam::run
