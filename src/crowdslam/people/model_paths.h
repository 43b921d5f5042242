#pragma once
// Where the detector models live and how a model name becomes files.
//
// Model directories, in order: $CROWDSLAM_MODELS, <repo>/models (installed there by
// scripts/install_models.sh), $CROWDSLAM_SHARED/models, else the compile-time ../shared/models.
// default_model_dir() is the first that exists (when none exists, the first candidate, so errors name a
// real path). A named model (model_zoo.h) is looked up in the first of these directories that holds its
// folder, so an older <repo>/models without the ONNX models still finds them in ../shared.
//
// resolve_model(spec): a zoo name ("body", "coco", "yolox", "bytetrack") -> its files, backend and
// preprocessing; "X.cfg" -> X.cfg + X.weights (Darknet); "X.onnx" -> the ONNX file (backend "auto":
// yolo-onnx unless Detector.backend says yolox). The files are not checked here; the detector checks
// them when it loads them.
#include <opencv2/core.hpp>
#include <string>

#include "crowdslam/people/model_zoo.h"

namespace crowdslam::people {

struct ModelFiles {
  std::string config;    // Darknet .cfg, or the .onnx file
  std::string weights;   // Darknet .weights; empty for ONNX
  int person_class = 0;  // person class index for the named models (0 for all of them)
  Backend backend = Backend::kAuto;  // kAuto: from the file name (resolved_backend)
  std::string preprocess;            // preset (preprocess.h); empty = the backend's default
  cv::Size detect_input;             // zoo models: `crowdslam detect`'s default input; 0x0 = none
  std::string name;                  // zoo name; empty for a path
};

// kAuto -> .onnx: kYoloOnnx, otherwise kDarknet.
Backend resolved_backend(const ModelFiles& model);
// The preprocessing preset name: model.preprocess, else "yolox" for the YOLOX backend, "darknet" otherwise.
std::string resolved_preprocess(const ModelFiles& model);

std::string default_model_dir();

// Throws InputError for a spec that is neither a known name nor a .cfg/.onnx path.
ModelFiles resolve_model(const std::string& spec);

}  // namespace crowdslam::people
