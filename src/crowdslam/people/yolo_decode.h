#pragma once
// Decoders of the raw output tensors of the detector backends, as pure functions (tested on crafted
// tensors). Each returns the person candidates with score >= confidence (and > 0) as centre + size in the
// decoder's own units; the detector maps them back to the image (preprocess.h), then clips them. (Centre
// form, so the Darknet boxes come out bit for bit as before: cx * image width - w * image width / 2.)
//
// decode_darknet   one 2-D output per yolo/region layer, rows [cx, cy, w, h, objectness, class scores],
//                  coordinates as FRACTIONS of the network input. OpenCV's region layer already multiplies
//                  the objectness into the class scores, so score = the person column as is.
// decode_yolo_onnx one output 1 x N x (5 + C), YOLOv5-style decoded exports: [cx, cy, w, h] in network
//                  pixels, score = objectness * class probability.
// decode_yolox     one output 1 x N x (5 + C), the raw YOLOX head (Megvii YOLOX, ByteTrack): rows ordered
//                  stride 8, 16, 32, each a row-major grid of (W / s) x (H / s) cells (gy outer, gx inner),
//                  N = sum over the strides of (W / s) (H / s). Per row [x, y, w, h, objectness, class
//                  scores]: centre = (grid + (x, y)) * s, size = exp(w, h) * s in network pixels. The export
//                  applies the sigmoid to objectness and class scores already (values in [0, 1], checked on
//                  both shared models), so score = objectness * class score.
// Errors (InputError naming `model_file`): a tensor of another shape than the backend's (e.g. a YOLOv5 export
// given as YOLOX: N = 3 x the YOLOX count), a person class beyond the model's classes.
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "crowdslam/people/detector.h"

namespace crowdslam::people {

struct CentreBox {
  float cx = 0, cy = 0, w = 0, h = 0;
  float score = 0;
};

struct DecodeOptions {
  int person_class = 0;
  double confidence = 0.2;
  std::string model_file;  // named in errors
};

std::vector<CentreBox> decode_darknet(const std::vector<cv::Mat>& outputs, const DecodeOptions& options);
std::vector<CentreBox> decode_yolo_onnx(const std::vector<cv::Mat>& outputs, const DecodeOptions& options);
std::vector<CentreBox> decode_yolox(const std::vector<cv::Mat>& outputs, cv::Size input,
                                    const DecodeOptions& options);

// The strides of the YOLOX head and the row count it has for an input size.
inline constexpr int kYoloxStrides[] = {8, 16, 32};
int yolox_rows(cv::Size input);

// "1x2184x85" for errors.
std::string shape_text(const cv::Mat& m);

}  // namespace crowdslam::people
