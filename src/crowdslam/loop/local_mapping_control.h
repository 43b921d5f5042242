#pragma once
// What loop closing and global BA need from local mapping: pause it while the map is corrected.
// Implemented by mapping::LocalMapper; an interface so that loop/ does not depend on mapping/.
namespace crowdslam::loop {

class LocalMappingControl {
 public:
  virtual ~LocalMappingControl() = default;
  // Asks the mapper to stop after the keyframe it is processing (a running local BA is aborted).
  // While paused, tracking creates no keyframes (KeyframeConsumer::is_paused()).
  virtual void request_pause() = 0;
  // Blocks until the mapper is paused (returns at once when it runs inline, in sequential mode).
  virtual void wait_until_paused() = 0;
  virtual void resume() = 0;
};

}  // namespace crowdslam::loop
