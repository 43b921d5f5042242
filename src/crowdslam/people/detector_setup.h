#pragma once
// The Detector.* settings -> the model and options of a DnnDetector, in one place for `crowdslam run`
// (System) and `crowdslam detect`.
//
//   model     spec_override (--detector / --model) if set, else Detector.model_cfg, else "body"; a zoo
//             name (model_zoo.h) or a .cfg / .onnx path. Detector.model_weights replaces the weights when
//             the model comes from the settings. Detector.person_class applies to paths (zoo models know
//             theirs).
//   backend   Detector.backend unless "auto" (e.g. "yolox" for a YOLOX .onnx given as a path)
//   preprocess Detector.preprocess unless "auto"
//   input     Detector.input_width x Detector.input_height when set, else the square Detector.input_size
//   resize    Detector.resize unless "auto" (stretch | letterbox over the preprocessing's own)
//   thresholds Detector.confidence, Detector.nms
// The settings are assumed checked (io::Settings::check); a value these parsers reject still throws an
// InputError naming the key.
#include <string>

#include "crowdslam/io/settings.h"
#include "crowdslam/people/detector.h"
#include "crowdslam/people/model_paths.h"

namespace crowdslam::people {

struct DetectorSetup {
  ModelFiles model;
  DetectorOptions options;
};

DetectorSetup detector_setup(const io::DetectorSettings& settings, const std::string& spec_override = "");

}  // namespace crowdslam::people
