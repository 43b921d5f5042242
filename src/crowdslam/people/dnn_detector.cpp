#include "crowdslam/people/dnn_detector.h"

#include <chrono>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "crowdslam/people/darknet_model.h"
#include "crowdslam/util/error.h"

namespace crowdslam::people {
namespace fs = std::filesystem;
namespace {

void require_model_file(const std::string& path) {
  std::error_code ec;
  if (path.empty()) throw InputError("detector model file not set");
  if (!fs::exists(path, ec))
    throw input_error(path, "model file not found (install the models with scripts/install_models.sh)");
  if (!fs::is_regular_file(path, ec)) throw input_error(path, "model path is not a file");
  if (fs::file_size(path, ec) == 0 || ec) throw input_error(path, "model file is empty or unreadable");
}

// First line of an OpenCV error (cv::Exception::what() is long and multi-line).
std::string short_message(const cv::Exception& e) { return e.err.empty() ? std::string(e.what()) : e.err; }

cv::Mat as_bgr(const cv::Mat& image) {
  if (image.channels() == 3) return image;
  cv::Mat bgr;
  if (image.channels() == 1)
    cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  else if (image.channels() == 4)
    cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR);
  else
    throw InputError("detector: unsupported image with " + std::to_string(image.channels()) + " channels");
  return bgr;
}

Preprocessing preprocessing_for(const ModelFiles& model, const DetectorOptions& options) {
  Preprocessing p = preprocessing_preset(resolved_preprocess(model));
  if (options.resize) p.resize = *options.resize;
  p.check();
  return p;
}

}  // namespace

std::vector<PersonBox> to_image_boxes(const std::vector<CentreBox>& candidates, Backend backend,
                                      const InputTransform& t) {
  // Darknet: fractions of the input; image_per_fraction is exactly the image size for a stretch, so
  // the product is the one the detector always computed.
  const bool fractions = backend == Backend::kDarknet;
  const auto fx = static_cast<float>(fractions ? t.image_per_fraction_x() : 1.0 / t.scale_x);
  const auto fy = static_cast<float>(fractions ? t.image_per_fraction_y() : 1.0 / t.scale_y);
  std::vector<PersonBox> boxes;
  boxes.reserve(candidates.size());
  for (const CentreBox& c : candidates) {
    const float w = c.w * fx;
    const float h = c.h * fy;
    const cv::Rect2f box(c.cx * fx - w / 2, c.cy * fy - h / 2, w, h);
    const PersonBox b{clip_box(box, t.image.width, t.image.height), c.score};
    if (b.box.width > 0 && b.box.height > 0) boxes.push_back(b);
  }
  return boxes;
}

DnnDetector::DnnDetector(const ModelFiles& model, const DetectorOptions& options)
    : model_(model), options_(options), backend_(resolved_backend(model)) {
  options_.check();
  input_ = options_.input();
  preprocessing_ = preprocessing_for(model_, options_);
  require_model_file(model_.config);
  const bool darknet = backend_ == Backend::kDarknet;
  if (darknet) require_model_file(model_.weights);
  name_ = fs::path(model_.config).stem().string() + "@" + input_size_text(input_);
  if (options_.opencv_threads > 0) cv::setNumThreads(options_.opencv_threads);
  try {
    net_ = darknet ? read_darknet(model_, options_.confidence) : cv::dnn::readNetFromONNX(model_.config);
  } catch (const cv::Exception& e) {
    const std::string& file = darknet ? model_.config + " / " + model_.weights : model_.config;
    throw input_error(file, "cannot load the model as " + std::string(to_string(backend_)) + ": " +
                                short_message(e));
  }
  if (net_.empty()) throw input_error(model_.config, "cannot load the model (OpenCV returned an empty net)");
  if (darknet) check_weights_size(net_, model_.weights);
  net_.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  net_.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  output_names_ = net_.getUnconnectedOutLayersNames();
  std::vector<cv::Mat> outputs;
  try {
    outputs = forward_raw(cv::Mat(input_, CV_8UC3, cv::Scalar::all(0)));
  } catch (const cv::Exception& e) {
    throw input_error(model_.config, "the model does not run at input " + input_size_text(input_) + ": " +
                                         short_message(e));
  }
  // Decode the warm-up output once with the lowest threshold so that a wrong output layout (e.g. a
  // YOLOv5 export declared as YOLOX) or an out-of-range person class is an error here, not mid-sequence.
  DecodeOptions probe{options_.person_class, 1.0, model_.config};
  if (backend_ == Backend::kYolox)
    decode_yolox(outputs, input_, probe);
  else if (backend_ == Backend::kYoloOnnx)
    decode_yolo_onnx(outputs, probe);
  else
    decode_darknet(outputs, probe);
}

std::vector<cv::Mat> DnnDetector::forward_raw(const cv::Mat& bgr, InputTransform* transform) {
  net_.setInput(make_input_blob(as_bgr(bgr), input_, preprocessing_, transform));
  std::vector<cv::Mat> outputs;
  net_.forward(outputs, output_names_);
  return outputs;
}

Detections DnnDetector::detect(const cv::Mat& bgr, std::size_t /*frame_index*/) {
  const auto start = std::chrono::steady_clock::now();
  if (bgr.empty()) throw InputError("detector " + name_ + ": empty image");
  std::vector<cv::Mat> outputs;
  InputTransform transform;
  try {
    outputs = forward_raw(bgr, &transform);
  } catch (const cv::Exception& e) {
    throw input_error(model_.config, "forward pass failed: " + short_message(e));
  }
  const DecodeOptions decode{options_.person_class, options_.confidence, model_.config};
  std::vector<CentreBox> candidates;
  if (backend_ == Backend::kYolox)
    candidates = decode_yolox(outputs, input_, decode);
  else if (backend_ == Backend::kYoloOnnx)
    candidates = decode_yolo_onnx(outputs, decode);
  else
    candidates = decode_darknet(outputs, decode);
  Detections result;
  result.raw = to_image_boxes(candidates, backend_, transform);
  result.boxes = suppress_non_maxima(result.raw, options_.confidence, options_.nms);
  result.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace crowdslam::people
