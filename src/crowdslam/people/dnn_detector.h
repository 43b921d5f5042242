#pragma once
// Person detector on OpenCV DNN (CPU) for every network backend of model_zoo.h:
//   darknet   .cfg + .weights through readNetFromDarknet (Yolo-Fastest 1.1, YOLOv3/-tiny family);
//   yolox     .onnx with the raw YOLOX head (YOLOX-nano COCO, ByteTrack-nano);
//   yolo-onnx .onnx with decoded YOLOv5-style output (best effort, no such model is shipped).
// Decoders: yolo_decode.h. Preprocessing (resize / letterbox, channel order, scale, mean, std) is
// declared per model (model_zoo.h, preprocess.h), never guessed from the tensor; DetectorOptions::resize
// can override the resize mode and DetectorOptions::input() sets any input of multiples of 32
// (e.g. 416x256).
//
// Boxes are mapped back to the image given to detect() through the exact inverse of the preprocessing
// (InputTransform), then clipped to it. With the default options and a Darknet model the boxes are bit
// for bit those of the former DarknetDetector.
//
// Threads: OpenCV DNN parallelises with cv::parallel_for_ whose thread count is process-wide
// (cv::setNumThreads). See DetectorOptions::opencv_threads. The first forward pass is run in the
// constructor (warm-up, and it turns a model that loads but cannot run, or an ONNX model whose output is
// not the backend's layout, into a clear error).
//
// Errors: a missing, empty or unreadable model file, one OpenCV cannot parse, an output of the wrong shape
// or a person class beyond the model's classes throw one InputError naming the file.
#include <opencv2/dnn.hpp>
#include <string>
#include <vector>

#include "crowdslam/people/detector.h"
#include "crowdslam/people/model_paths.h"
#include "crowdslam/people/preprocess.h"
#include "crowdslam/people/yolo_decode.h"

namespace crowdslam::people {

class DnnDetector : public PersonDetector {
 public:
  DnnDetector(const ModelFiles& model, const DetectorOptions& options);

  Detections detect(const cv::Mat& bgr, std::size_t frame_index) override;
  [[nodiscard]] std::string name() const override { return name_; }

  // One forward pass, undecoded: the network's output layers (for inspection in tests and docs), and the
  // transform that maps network coordinates back to `bgr`.
  std::vector<cv::Mat> forward_raw(const cv::Mat& bgr, InputTransform* transform = nullptr);

  [[nodiscard]] Backend backend() const { return backend_; }
  [[nodiscard]] const Preprocessing& preprocessing() const { return preprocessing_; }
  [[nodiscard]] cv::Size input() const { return input_; }

 private:
  ModelFiles model_;
  DetectorOptions options_;
  Backend backend_ = Backend::kDarknet;
  Preprocessing preprocessing_;
  cv::Size input_;
  std::string name_;
  cv::dnn::Net net_;
  std::vector<std::string> output_names_;
};

// Decoded candidates (in the backend's units: fractions of the input for darknet, network pixels
// otherwise) -> boxes in image pixels, clipped to the image; boxes with nothing left are dropped.
std::vector<PersonBox> to_image_boxes(const std::vector<CentreBox>& candidates, Backend backend,
                                      const InputTransform& transform);

}  // namespace crowdslam::people
