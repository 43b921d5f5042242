#include "crowdslam/people/model_zoo.h"

#include "crowdslam/util/error.h"

namespace crowdslam::people {

Backend parse_backend(const std::string& text, const std::string& key) {
  if (text == "auto") return Backend::kAuto;
  if (text == "darknet") return Backend::kDarknet;
  if (text == "yolo-onnx") return Backend::kYoloOnnx;
  if (text == "yolox") return Backend::kYolox;
  throw InputError(key + ": expected \"auto\", \"darknet\", \"yolo-onnx\" or \"yolox\", got \"" + text + "\"");
}

const char* to_string(Backend backend) {
  switch (backend) {
    case Backend::kAuto: return "auto";
    case Backend::kDarknet: return "darknet";
    case Backend::kYoloOnnx: return "yolo-onnx";
    case Backend::kYolox: return "yolox";
  }
  return "?";
}

const std::vector<ZooModel>& model_zoo() {
  // detect_input: the input `crowdslam detect` uses when neither the command line nor a settings file
  // gives one: the best pooled MODA of each model on the three MOT sequences at conf 0.3 / NMS 0.45
  // (docs/DETECTION.md; the SLAM default is in config/*.yaml). All are 4:3-ish, as those frames.
  static const std::vector<ZooModel> zoo = {
      {"body", "yolo-fastest-1.1", "yolo-fastest-1.1_body.cfg", "yolo-fastest-1.1_body.weights",
       Backend::kDarknet, "darknet", 1, 0, {416, 320}, "Yolo-Fastest 1.1, person only (the SLAM default)"},
      {"coco", "yolo-fastest-1.1", "yolo-fastest-1.1.cfg", "yolo-fastest-1.1.weights", Backend::kDarknet,
       "darknet", 80, 0, {416, 320}, "Yolo-Fastest 1.1, COCO (person = class 0)"},
      {"yolox", "yolox-nano", "yolox_nano.onnx", "", Backend::kYolox, "yolox", 80, 0, {320, 256},
       "YOLOX-nano, COCO (person = class 0)"},
      {"bytetrack", "bytetrack-nano", "bytetrack_nano.onnx", "", Backend::kYolox, "bytetrack", 1, 0, {416, 320},
       "YOLOX-nano trained on people by ByteTrack (CrowdHuman, MOT17, CityPersons, ETHZ)"},
  };
  return zoo;
}

const ZooModel* find_zoo_model(const std::string& name) {
  for (const ZooModel& m : model_zoo())
    if (m.name == name) return &m;
  return nullptr;
}

std::string zoo_model_names() {
  std::string names;
  for (const ZooModel& m : model_zoo()) names += (names.empty() ? "" : ", ") + m.name;
  return names;
}

}  // namespace crowdslam::people
