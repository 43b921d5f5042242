#pragma once
// Network input preparation for the OpenCV DNN detectors, and the exact inverse mapping of boxes.
//
// Two resize modes:
//   kStretch   the whole image is resized to the input size, each axis on its own (Darknet and the
//              original Crowd-SLAM; aspect-true only when the input has the image's aspect, e.g. 416x320
//              for 640x480);
//   kLetterbox the image is resized by one factor r = min(W / w, H / h) to (int(w r), int(h r)) (the
//              truncation of YOLOX's preproc) and placed at the top-left corner of a W x H canvas filled
//              with `pad_value`; the bottom/right rest is padding.
// Then every channel value v (0-255, in the network's channel order) becomes (v * scale - mean) / std.
//
// InputTransform: network pixel = image pixel * (scale_x, scale_y), with scale_x = resized.width / w
// (and y alike). That is what cv::resize does with pixel edges at integer coordinates, so a box found at
// network coordinates maps back exactly to the image by dividing by the same factors. With kLetterbox the
// factors of the two axes differ slightly (the truncation); they are used as they are, not r.
#include <opencv2/core.hpp>
#include <string>

namespace crowdslam::people {

enum class ResizeMode { kStretch, kLetterbox };

struct Preprocessing {
  bool rgb = true;            // channel order the network wants (the image is BGR)
  double scale = 1.0 / 255.0;  // v * scale ...
  cv::Scalar mean{0, 0, 0};   // ... - mean[c] ... (network channel order, after scale)
  cv::Scalar std{1, 1, 1};    // ... / std[c]
  ResizeMode resize = ResizeMode::kStretch;
  double pad_value = 114.0;  // letterbox padding, a 0-255 pixel value (normalised like the image)
  std::string name = "darknet";  // preset name, for logs and errors

  void check() const;  // InputError naming the bad value
};

// Presets by name: "darknet" (RGB, / 255, stretch: Darknet and Yolo-Fastest), "yolox" (BGR, 0-255,
// letterbox padded with 114: YOLOX COCO models), "bytetrack" (RGB, / 255, ImageNet mean and std,
// letterbox padded with 114 before normalisation: the ByteTrack YOLOX models). InputError naming `key`
// and the value for anything else.
Preprocessing preprocessing_preset(const std::string& name, const std::string& key = "Detector.preprocess");
ResizeMode parse_resize_mode(const std::string& text, const std::string& key = "Detector.resize");
const char* to_string(ResizeMode mode);

struct InputTransform {
  cv::Size image;    // original image size
  cv::Size input;    // network input size
  cv::Size resized;  // the image's area in the network input (== input for kStretch)
  double scale_x = 1.0;  // network x = image x * scale_x
  double scale_y = 1.0;

  // Box in network-input pixels -> box in image pixels (not clipped).
  [[nodiscard]] cv::Rect2f to_image(const cv::Rect2f& network_box) const;
  // Box in image pixels -> network-input pixels.
  [[nodiscard]] cv::Rect2f to_network(const cv::Rect2f& image_box) const;
  // Image pixels per unit of a coordinate given as a fraction of the network input (Darknet outputs):
  // input.width / scale_x. Computed as (input.width * image.width) / resized.width in double, which is
  // exactly image.width for kStretch, so the Darknet boxes are the same as before the letterbox option.
  [[nodiscard]] double image_per_fraction_x() const;
  [[nodiscard]] double image_per_fraction_y() const;
};

InputTransform make_input_transform(cv::Size image, cv::Size input, ResizeMode mode);

// The resized (and for kLetterbox, padded) 8-bit BGR image of the network input size.
cv::Mat resize_for_network(const cv::Mat& bgr, const InputTransform& transform, const Preprocessing& pre);

// NCHW float blob (1 x 3 x H x W) of an 8-bit BGR image, and the transform that maps boxes back.
// For kStretch with mean 0 and std 1 this is exactly the former
// blobFromImage(image, scale, input, Scalar(), swapRB = rgb, crop = false).
cv::Mat make_input_blob(const cv::Mat& bgr, cv::Size input, const Preprocessing& pre,
                        InputTransform* transform = nullptr);

}  // namespace crowdslam::people
