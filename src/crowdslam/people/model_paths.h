#pragma once
// Where the detector models live and how a model name becomes files.
//
// default_model_dir(): the first that exists of
//   1. $CROWDSLAM_MODELS
//   2. <repo>/models            (installed there by scripts/install_models.sh)
//   3. $CROWDSLAM_SHARED/models, else the compile-time ../shared/models
// (when none exists, the first candidate that is set is returned, so errors name a real path).
//
// resolve_model(spec): "body" -> yolo-fastest-1.1/yolo-fastest-1.1_body.{cfg,weights} (1 class: person),
// "coco" -> yolo-fastest-1.1/yolo-fastest-1.1.{cfg,weights} (COCO, person = class 0),
// "X.cfg" -> X.cfg + X.weights, "X.onnx" -> the ONNX file. The files are not checked here; the detector
// checks them when it loads them.
#include <string>

namespace crowdslam::people {

struct ModelFiles {
  std::string config;    // Darknet .cfg, or the .onnx file
  std::string weights;   // Darknet .weights; empty for ONNX
  int person_class = 0;  // person class index for the named models (0 for both Yolo-Fastest models)
};

std::string default_model_dir();

// Throws InputError for a spec that is neither a known name nor a .cfg/.onnx path.
ModelFiles resolve_model(const std::string& spec);

}  // namespace crowdslam::people
