#pragma once
// Former name of DnnDetector (dnn_detector.h), kept so existing callers (system/, bench/) build unchanged.
#include "crowdslam/people/dnn_detector.h"

namespace crowdslam::people {

using DarknetDetector = DnnDetector;

}  // namespace crowdslam::people
