#include "crowdslam/run/sensor_pacer.h"

#include <thread>

namespace crowdslam::run {

bool SensorPacer::admit(double stamp_s) {
  const auto now = Clock::now();
  if (!start_) {
    start_ = now;
    first_stamp_s_ = stamp_s;
    previous_stamp_s_ = stamp_s;
    return true;
  }
  const double gap_s = previous_stamp_s_ && stamp_s > *previous_stamp_s_ ? stamp_s - *previous_stamp_s_ : 0.0;
  previous_stamp_s_ = stamp_s;
  const auto arrival = *start_ + std::chrono::duration_cast<Clock::duration>(
                                     std::chrono::duration<double>(stamp_s - first_stamp_s_));
  if (now < arrival) {
    std::this_thread::sleep_until(arrival);
    return true;
  }
  const auto stale_at = arrival + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(gap_s));
  if (gap_s > 0 && now >= stale_at) {
    ++dropped_;
    return false;
  }
  return true;
}

}  // namespace crowdslam::run
