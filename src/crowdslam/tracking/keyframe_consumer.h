#pragma once
// What tracking needs from local mapping, as an interface so tracking does not depend on the mapper
// (and tests can substitute a sequential one).
#include <cstddef>
#include <cstdint>
#include <memory>

namespace crowdslam::map {
class KeyFrame;
}

namespace crowdslam::tracking {

class KeyframeConsumer {
 public:
  virtual ~KeyframeConsumer() = default;
  virtual void insert_keyframe(std::shared_ptr<map::KeyFrame> keyframe) = 0;
  // Both queued at once (a two-view map's keyframes): the mapper never sees the first alone, as in
  // sequential mode, so it never fuses or adjusts it before the second is there.
  virtual void insert_keyframes(std::shared_ptr<map::KeyFrame> first, std::shared_ptr<map::KeyFrame> second) = 0;
  // True when the mapper is idle and would take a keyframe right away.
  [[nodiscard]] virtual bool accepts_keyframes() const = 0;
  [[nodiscard]] virtual size_t queued_keyframes() const = 0;
  // Blocks until the mapper accepts keyframes (idle, empty queue), is paused or stopped, or `timeout_ms`
  // passes. Returns accepts_keyframes(). Call without holding the map-update lock (the mapper takes it to
  // write bundle adjustment results back).
  virtual bool wait_until_accepting(double timeout_ms) = 0;
  // Asks a running local BA to stop early (a new keyframe is more useful).
  virtual void interrupt_bundle_adjustment() = 0;
  // True while the mapper is paused (e.g. loop correction): no keyframes are created then.
  [[nodiscard]] virtual bool is_paused() const = 0;
};

}  // namespace crowdslam::tracking
