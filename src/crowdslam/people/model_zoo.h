#pragma once
// The person-detector models crowdslam knows by name, with everything needed to run them: files,
// backend (decoder), preprocessing, classes, person class and the input `crowdslam detect` uses by default.
// One table used by `crowdslam run` (--detector, Detector.model_cfg) and `crowdslam detect` (--model).
//
// | name      | folder            | backend | preprocessing | classes | detect default input |
// | body      | yolo-fastest-1.1  | darknet | darknet       | 1       | 416x320              |
// | coco      | yolo-fastest-1.1  | darknet | darknet       | 80      | 416x320              |
// | yolox     | yolox-nano        | yolox   | yolox         | 80      | 320x256              |
// | bytetrack | bytetrack-nano    | yolox   | bytetrack     | 1       | 416x320              |
//
// Backends (decoders, yolo_decode.h): darknet (.cfg + .weights through readNetFromDarknet), yolo-onnx
// (decoded YOLOv5-style ONNX exports, the former best-effort ONNX path), yolox (raw YOLOX head).
// A model given as a path has backend "auto": .onnx -> yolo-onnx, anything else -> darknet; say
// Detector.backend: yolox (crowdslam detect --backend yolox) for a YOLOX export.
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace crowdslam::people {

enum class Backend { kAuto, kDarknet, kYoloOnnx, kYolox };

// "auto", "darknet", "yolo-onnx", "yolox"; InputError naming `key` and the value otherwise.
Backend parse_backend(const std::string& text, const std::string& key = "Detector.backend");
const char* to_string(Backend backend);

struct ZooModel {
  std::string name;
  std::string folder;   // below the model directory (model_paths.h)
  std::string config;   // .cfg or .onnx
  std::string weights;  // .weights; empty for ONNX
  Backend backend = Backend::kDarknet;
  std::string preprocess;  // preset name (preprocess.h)
  int classes = 1;
  int person_class = 0;
  cv::Size detect_input;  // `crowdslam detect`'s default input for this model (quality, docs/DETECTION.md)
  std::string about;
};

const std::vector<ZooModel>& model_zoo();
const ZooModel* find_zoo_model(const std::string& name);  // nullptr when unknown
std::string zoo_model_names();                            // "body, coco, yolox, bytetrack"

}  // namespace crowdslam::people
