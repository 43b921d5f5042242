#include "crowdslam/people/preprocess.h"

#include <algorithm>
#include <cmath>
#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "crowdslam/util/error.h"

namespace crowdslam::people {
namespace {

bool is_identity(const Preprocessing& p) {
  return p.mean == cv::Scalar(0, 0, 0) && p.std == cv::Scalar(1, 1, 1);
}

}  // namespace

void Preprocessing::check() const {
  std::ostringstream problem;
  if (!(std::isfinite(scale) && scale > 0)) problem << "scale must be > 0, got " << scale;
  for (int c = 0; c < 3 && problem.str().empty(); ++c) {
    if (!std::isfinite(mean[c])) problem << "mean[" << c << "] must be finite, got " << mean[c];
    if (!(std::isfinite(std[c]) && std[c] > 0)) problem << "std[" << c << "] must be > 0, got " << std[c];
  }
  if (problem.str().empty() && !(pad_value >= 0 && pad_value <= 255))
    problem << "pad_value must be in [0, 255], got " << pad_value;
  if (!problem.str().empty()) throw InputError("detector preprocessing '" + name + "': " + problem.str());
}

Preprocessing preprocessing_preset(const std::string& name, const std::string& key) {
  Preprocessing p;
  p.name = name;
  if (name == "darknet") return p;  // the defaults: RGB, / 255, stretch
  if (name == "yolox") {
    // YOLOX COCO weights (Megvii's demo and opencv_zoo): BGR as read, no scaling, no normalisation.
    p.rgb = false;
    p.scale = 1.0;
    p.resize = ResizeMode::kLetterbox;
    return p;
  }
  if (name == "bytetrack") {
    // ByteTrack's preproc: pad with 114, BGR -> RGB, / 255, then ImageNet mean / std.
    p.resize = ResizeMode::kLetterbox;
    p.mean = cv::Scalar(0.485, 0.456, 0.406);
    p.std = cv::Scalar(0.229, 0.224, 0.225);
    return p;
  }
  throw InputError(key + ": expected \"darknet\", \"yolox\" or \"bytetrack\", got \"" + name + "\"");
}

ResizeMode parse_resize_mode(const std::string& text, const std::string& key) {
  if (text == "stretch") return ResizeMode::kStretch;
  if (text == "letterbox") return ResizeMode::kLetterbox;
  throw InputError(key + ": expected \"stretch\" or \"letterbox\", got \"" + text + "\"");
}

const char* to_string(ResizeMode mode) { return mode == ResizeMode::kStretch ? "stretch" : "letterbox"; }

cv::Rect2f InputTransform::to_image(const cv::Rect2f& b) const {
  return {static_cast<float>(b.x / scale_x), static_cast<float>(b.y / scale_y),
          static_cast<float>(b.width / scale_x), static_cast<float>(b.height / scale_y)};
}

cv::Rect2f InputTransform::to_network(const cv::Rect2f& b) const {
  return {static_cast<float>(b.x * scale_x), static_cast<float>(b.y * scale_y),
          static_cast<float>(b.width * scale_x), static_cast<float>(b.height * scale_y)};
}

double InputTransform::image_per_fraction_x() const {
  return static_cast<double>(input.width) * image.width / resized.width;
}

double InputTransform::image_per_fraction_y() const {
  return static_cast<double>(input.height) * image.height / resized.height;
}

InputTransform make_input_transform(cv::Size image, cv::Size input, ResizeMode mode) {
  CV_Assert(image.width > 0 && image.height > 0 && input.width > 0 && input.height > 0);
  InputTransform t;
  t.image = image;
  t.input = input;
  t.resized = input;
  if (mode == ResizeMode::kLetterbox) {
    // r = min(W / w, H / h); the limiting axis fills the input, the other is truncated as int(w * r).
    // In integers (64-bit), so 480 * (256 / 480) cannot come out as 255.
    const long long w = image.width, h = image.height, W = input.width, H = input.height;
    if (W * h <= H * w)
      t.resized = cv::Size(input.width, static_cast<int>(std::max(1LL, h * W / w)));
    else
      t.resized = cv::Size(static_cast<int>(std::max(1LL, w * H / h)), input.height);
  }
  t.scale_x = static_cast<double>(t.resized.width) / image.width;
  t.scale_y = static_cast<double>(t.resized.height) / image.height;
  return t;
}

cv::Mat resize_for_network(const cv::Mat& bgr, const InputTransform& t, const Preprocessing& pre) {
  CV_Assert(bgr.type() == CV_8UC3 && bgr.size() == t.image);
  cv::Mat resized;
  if (t.resized == t.image)
    resized = bgr;
  else
    cv::resize(bgr, resized, t.resized, 0, 0, cv::INTER_LINEAR);
  if (t.resized == t.input) return resized;
  cv::Mat canvas(t.input, CV_8UC3, cv::Scalar::all(pre.pad_value));
  resized.copyTo(canvas(cv::Rect(0, 0, t.resized.width, t.resized.height)));
  return canvas;
}

cv::Mat make_input_blob(const cv::Mat& bgr, cv::Size input, const Preprocessing& pre, InputTransform* transform) {
  const InputTransform t = make_input_transform(bgr.size(), input, pre.resize);
  if (transform) *transform = t;
  // Stretch: blobFromImage resizes itself (INTER_LINEAR), as the detector always did.
  const cv::Mat source = pre.resize == ResizeMode::kStretch ? bgr : resize_for_network(bgr, t, pre);
  cv::Mat blob = cv::dnn::blobFromImage(source, pre.scale, input, cv::Scalar(), pre.rgb, /*crop=*/false);
  if (is_identity(pre)) return blob;
  // (v * scale - mean) / std per channel plane; blob is 1 x 3 x H x W, continuous.
  const int plane = input.width * input.height;
  for (int c = 0; c < 3; ++c) {
    cv::Mat channel(1, plane, CV_32F, blob.ptr<float>(0, c));
    channel.convertTo(channel, CV_32F, 1.0 / pre.std[c], -pre.mean[c] / pre.std[c]);
  }
  return blob;
}

}  // namespace crowdslam::people
