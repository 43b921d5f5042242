#pragma once
// Person detector on OpenCV DNN (CPU): Darknet YOLO models (.cfg + .weights: YOLOv3/-tiny family,
// Yolo-Fastest 1.1) and, best effort, YOLO ONNX exports.
//
// Pre-processing: cv::dnn::blobFromImage(image, 1/255, input_size x input_size, swapRB = true, no crop):
// the whole image is stretched to the square input (as Darknet and the original Crowd-SLAM do).
//
// Darknet output (every unconnected output layer, one row per anchor and cell):
//   [cx, cy, w, h, objectness, score_0 .. score_C-1], coordinates normalised to [0, 1] of the image.
// OpenCV's region/yolo layer already multiplies the objectness into the class scores, so the person
// confidence is score_{person_class} as is (checked on a bonn_crowd frame: every class score <= its
// objectness; tests/people/test_darknet_detector.cpp). That layer also zeroes scores below its own
// threshold, the cfg key `thresh` of [yolo]/[region] sections, default 0.2; the cfg is therefore loaded
// with `thresh=<confidence>` added to those sections (unless the cfg sets it), so confidence thresholds
// below 0.2 take effect.
//
// ONNX (file name ends in .onnx; no test model is shipped, only the error path is tested): one output
// of shape 1 x N x (5 + C) as written by YOLOv5-style exports: [cx, cy, w, h, objectness, class
// probabilities], coordinates in network-input pixels; confidence = objectness * class probability.
//
// Threads: OpenCV DNN parallelises with cv::parallel_for_ whose thread count is process-wide
// (cv::setNumThreads). See DetectorOptions::opencv_threads. The first forward pass is run in the
// constructor (warm-up, and it turns a model that loads but cannot run into a clear error).
//
// Errors: a missing, empty or unreadable model file, or one OpenCV cannot parse, throws one InputError
// naming the file.
#include <opencv2/dnn.hpp>
#include <string>
#include <vector>

#include "crowdslam/people/detector.h"
#include "crowdslam/people/model_paths.h"

namespace crowdslam::people {

class DarknetDetector : public PersonDetector {
 public:
  DarknetDetector(const ModelFiles& model, const DetectorOptions& options);

  Detections detect(const cv::Mat& bgr, std::size_t frame_index) override;
  [[nodiscard]] std::string name() const override { return name_; }

  // One forward pass, undecoded: the network's output layers (for inspection in tests and docs).
  std::vector<cv::Mat> forward_raw(const cv::Mat& bgr);

 private:
  void decode_darknet(const std::vector<cv::Mat>& outputs, cv::Size image, std::vector<PersonBox>& raw) const;
  void decode_onnx(const std::vector<cv::Mat>& outputs, cv::Size image, std::vector<PersonBox>& raw) const;

  ModelFiles model_;
  DetectorOptions options_;
  bool onnx_ = false;
  std::string name_;
  cv::dnn::Net net_;
  std::vector<std::string> output_names_;
};

}  // namespace crowdslam::people
