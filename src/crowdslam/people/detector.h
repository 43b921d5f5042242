#pragma once
// Person detectors: the interface the SLAM system and the `crowdslam detect` tool use, and the options
// shared by every backend.
//
// Backends: DnnDetector (OpenCV DNN: Darknet .cfg/.weights, YOLOX and YOLOv5-style .onnx exports;
// dnn_detector.h, formerly DarknetDetector) and MotFileDetector (boxes read from a MOT-format file;
// mot_file_detector.h).
//
// Boxes are in pixels of the image given to detect(): x, y = top-left corner, clipped to the image.
// `raw` keeps every box above the confidence threshold before non-maximum suppression (the original
// Crowd-SLAM masked with those), `boxes` the ones NMS kept.
#include <cstddef>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "crowdslam/people/preprocess.h"

namespace crowdslam::people {

struct PersonBox {
  cv::Rect2f box;  // x, y, width, height in pixels
  float confidence = 0.0f;
};

struct Detections {
  std::vector<PersonBox> boxes;  // after NMS
  std::vector<PersonBox> raw;    // every box above the confidence threshold, before NMS
  double time_ms = 0.0;          // time spent in detect() (network forward and decoding)
};

struct DetectorOptions {
  // Network input: input_width x input_height when both are set (> 0), else input_size x input_size
  // (the square shorthand of older settings files). Each a multiple of 32, in 32..kMaxInputSide.
  int input_size = 160;
  int input_width = 0;
  int input_height = 0;
  // How the image becomes the input; unset = the model's preprocessing (stretch for Darknet, letterbox
  // for YOLOX). Letterbox keeps the aspect for any input size; stretch is aspect-true when the input
  // has the image's aspect.
  std::optional<ResizeMode> resize;
  double confidence = 0.2;  // boxes with a person score below this are dropped
  double nms = 0.1;         // IoU threshold of non-maximum suppression
  int person_class = 0;     // class index of "person" in the model's output
  // DarknetDetector: when > 0, cv::setNumThreads(opencv_threads) is called when the detector is created.
  // OpenCV DNN parallelises layers with cv::parallel_for_, and that setting is PROCESS-WIDE (it also
  // affects cv::resize etc. in every thread). Default 1: the detector runs on its own thread beside ORB
  // extraction, so one core each is what a 2-core machine wants. 0 = leave OpenCV's setting alone (the
  // SLAM system / caller decides).
  int opencv_threads = 1;

  [[nodiscard]] cv::Size input() const;
  void check() const;  // throws InputError naming the bad value
};

inline constexpr int kMaxInputSide = 2048;

// "416x256" or "320" (square) -> size; InputError naming `key` unless each side is a multiple of 32 in
// 32..kMaxInputSide.
cv::Size parse_input_size(const std::string& text, const std::string& key);
std::string input_size_text(cv::Size size);  // "416x256"; "160" when square

class PersonDetector {
 public:
  PersonDetector() = default;
  virtual ~PersonDetector() = default;
  PersonDetector(const PersonDetector&) = delete;
  PersonDetector& operator=(const PersonDetector&) = delete;

  // Detects people in an 8-bit BGR (or grey) image. frame_index is the 0-based frame number in the
  // sequence (file-based detectors look boxes up by it; network detectors ignore it).
  virtual Detections detect(const cv::Mat& bgr, std::size_t frame_index) = 0;
  [[nodiscard]] virtual std::string name() const = 0;
  // False when the boxes come from frame_index alone (a file), so the pixels are not looked at.
  [[nodiscard]] virtual bool reads_pixels() const { return true; }
};

// Clips a box to [0, width) x [0, height). Returns an empty rect (width or height <= 0) when nothing is
// left; NaN coordinates give an empty rect too.
cv::Rect2f clip_box(const cv::Rect2f& box, int width, int height);

// Intersection over union (0 for empty boxes).
double box_iou(const cv::Rect2f& a, const cv::Rect2f& b);

// Non-maximum suppression (cv::dnn::NMSBoxes with score threshold `confidence` and IoU threshold `nms`);
// keeps the order of decreasing confidence.
std::vector<PersonBox> suppress_non_maxima(const std::vector<PersonBox>& boxes, double confidence,
                                           double nms);

// Index of the box in `candidates` that `box` overlaps most (by IoU), -1 when it overlaps none: for a raw
// box, the NMS box it duplicates.
int most_overlapping(const cv::Rect2f& box, const std::vector<PersonBox>& candidates);

// The raw (before-NMS) boxes that outline the person of an NMS box: each raw box's leader is the NMS box
// it overlaps most (by IoU); a raw box more than `max_area_ratio` times its leader's area (or overlapping
// no NMS box) is dropped and counted in `*dropped`. A low NMS threshold (the paper's 0.1) lets a box
// spanning most of the image be suppressed by a person's box; as a mask it would hide the whole scene.
// max_area_ratio <= 0 keeps every raw box.
std::vector<PersonBox> raw_boxes_near_leaders(const Detections& detections, double max_area_ratio,
                                              int* dropped = nullptr);

}  // namespace crowdslam::people
