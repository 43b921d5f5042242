#pragma once
// Loading Darknet models through OpenCV DNN, with the checks OpenCV does not do itself (used by
// DnnDetector, dnn_detector.h).
#include <opencv2/dnn.hpp>

#include "crowdslam/people/model_paths.h"

namespace crowdslam::people {

// readNetFromDarknet with `thresh=<confidence>` added to every [yolo]/[region] section that does not set
// it: OpenCV's region layer zeroes every class score below its own `thresh` (default 0.2), so without it
// confidence thresholds below 0.2 would silently act like 0.2.
cv::dnn::Net read_darknet(const ModelFiles& model, double confidence);

// Darknet .weights = header (major, minor, revision as int32, then `seen` as int64 from version 0.2 on,
// int32 before) + every learned float in layer order. OpenCV does not notice a short file (it reads
// zeros), so the size is checked against the parameters the loaded network holds. InputError naming the
// file when it is too short; a warning when it is longer.
void check_weights_size(const cv::dnn::Net& net, const std::string& weights);

}  // namespace crowdslam::people
