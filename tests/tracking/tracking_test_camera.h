#pragma once
// The camera of the tracking tests built in closed form: 640 x 480, f 525, no distortion, and RGB-D's
// virtual stereo baseline (bf 40).
#include <memory>

#include "crowdslam/geometry/camera.h"

namespace crowdslam::test {

inline std::shared_ptr<geometry::PinholeCamera> rgbd_test_camera() {
  auto c = std::make_shared<geometry::PinholeCamera>();
  c->fx = c->fy = 525;
  c->cx = 319.5;
  c->cy = 239.5;
  c->width = 640;
  c->height = 480;
  c->bf = 40;  // RGB-D's virtual baseline
  return c;
}

}  // namespace crowdslam::test
