#include "crowdslam/people/darknet_detector.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::people {
namespace fs = std::filesystem;
namespace {

bool ends_with(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

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

PersonBox make_box(float cx, float cy, float w, float h, float confidence, cv::Size image) {
  const cv::Rect2f box(cx - w / 2, cy - h / 2, w, h);
  return {clip_box(box, image.width, image.height), confidence};
}

// Darknet .weights = header (major, minor, revision as int32, then `seen` as int64 from version 0.2 on,
// int32 before) + every learned float in layer order. OpenCV does not notice a short file (it reads
// zeros), so the size is checked against the parameters the loaded network holds (all layer blobs except
// the Region layers' anchors, which come from the cfg).
void check_weights_size(const cv::dnn::Net& net, const std::string& weights) {
  std::ifstream in(weights, std::ios::binary);
  std::int32_t version[3] = {0, 0, 0};
  in.read(reinterpret_cast<char*>(version), sizeof(version));
  if (!in) throw input_error(weights, "model file too short for a Darknet weights header");
  const bool long_seen = version[0] * 10 + version[1] >= 2 && version[0] < 1000 && version[1] < 1000;
  std::uintmax_t floats = 0;
  for (const std::string& name : net.getLayerNames()) {
    const cv::Ptr<cv::dnn::Layer> layer = net.getLayer(name);
    if (layer->type == "Region") continue;
    for (const cv::Mat& blob : layer->blobs) floats += blob.total();
  }
  const std::uintmax_t expected = 12 + (long_seen ? 8 : 4) + 4 * floats;
  const std::uintmax_t actual = fs::file_size(weights);
  if (actual < expected)
    throw input_error(weights, "truncated or not matching the cfg: " + std::to_string(actual) +
                                   " bytes, the network needs " + std::to_string(expected));
  if (actual > expected)
    spdlog::warn("{}: {} bytes, the network uses only {} (weights for a different cfg?)", weights, actual,
                 expected);
}

std::string read_binary(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) throw input_error(path, "cannot read model file");
  return bytes;
}

// OpenCV's region layer zeroes every class score below its own `thresh` (default 0.2, the [yolo]/[region]
// key `thresh`). So that confidence thresholds below 0.2 work, `thresh=<confidence>` is added to every
// such section that does not set it.
std::string cfg_with_threshold(const std::string& cfg_path, double confidence) {
  std::ostringstream out;
  bool in_output_section = false;
  bool has_thresh = false;
  const auto close_section = [&] {
    if (in_output_section && !has_thresh) out << "thresh=" << confidence << '\n';
  };
  for (const std::string& raw : read_lines(cfg_path)) {
    const std::string line = trim(raw);
    if (!line.empty() && line[0] == '[') {
      close_section();
      in_output_section = line == "[yolo]" || line == "[region]";
      has_thresh = false;
    } else if (in_output_section) {
      const std::string key = trim(line.substr(0, line.find('=')));
      if (key == "thresh") has_thresh = true;
    }
    out << raw << '\n';
  }
  close_section();
  return out.str();
}

cv::dnn::Net read_darknet(const ModelFiles& model, double confidence) {
  const std::string cfg = cfg_with_threshold(model.config, confidence);
  const std::string weights = read_binary(model.weights);
  return cv::dnn::readNetFromDarknet(cfg.data(), cfg.size(), weights.data(), weights.size());
}

}  // namespace

DarknetDetector::DarknetDetector(const ModelFiles& model, const DetectorOptions& options)
    : model_(model), options_(options), onnx_(ends_with(model.config, ".onnx")) {
  options_.check();
  require_model_file(model_.config);
  if (!onnx_) require_model_file(model_.weights);
  name_ = fs::path(model_.config).stem().string() + "@" + std::to_string(options_.input_size);
  if (options_.opencv_threads > 0) cv::setNumThreads(options_.opencv_threads);
  try {
    net_ = onnx_ ? cv::dnn::readNetFromONNX(model_.config) : read_darknet(model_, options_.confidence);
  } catch (const cv::Exception& e) {
    const std::string& file = onnx_ ? model_.config : model_.config + " / " + model_.weights;
    throw input_error(file, "cannot load the model: " + short_message(e));
  }
  if (net_.empty()) throw input_error(model_.config, "cannot load the model (OpenCV returned an empty net)");
  if (!onnx_) check_weights_size(net_, model_.weights);
  net_.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  net_.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  output_names_ = net_.getUnconnectedOutLayersNames();
  try {
    forward_raw(cv::Mat(options_.input_size, options_.input_size, CV_8UC3, cv::Scalar::all(0)));
  } catch (const cv::Exception& e) {
    throw input_error(model_.config, "the model does not run: " + short_message(e));
  }
}

std::vector<cv::Mat> DarknetDetector::forward_raw(const cv::Mat& bgr) {
  const cv::Mat blob =
      cv::dnn::blobFromImage(as_bgr(bgr), 1.0 / 255.0, cv::Size(options_.input_size, options_.input_size),
                             cv::Scalar(), /*swapRB=*/true, /*crop=*/false);
  net_.setInput(blob);
  std::vector<cv::Mat> outputs;
  net_.forward(outputs, output_names_);
  return outputs;
}

Detections DarknetDetector::detect(const cv::Mat& bgr, std::size_t /*frame_index*/) {
  const auto start = std::chrono::steady_clock::now();
  if (bgr.empty()) throw InputError("detector " + name_ + ": empty image");
  std::vector<cv::Mat> outputs;
  try {
    outputs = forward_raw(bgr);
  } catch (const cv::Exception& e) {
    throw input_error(model_.config, "forward pass failed: " + short_message(e));
  }
  Detections result;
  if (onnx_)
    decode_onnx(outputs, bgr.size(), result.raw);
  else
    decode_darknet(outputs, bgr.size(), result.raw);
  result.boxes = suppress_non_maxima(result.raw, options_.confidence, options_.nms);
  result.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

void DarknetDetector::decode_darknet(const std::vector<cv::Mat>& outputs, cv::Size image,
                                     std::vector<PersonBox>& raw) const {
  const int column = 5 + options_.person_class;
  for (const cv::Mat& out : outputs) {
    if (out.dims != 2 || out.type() != CV_32F) throw input_error(model_.config, "unexpected output layout");
    if (out.cols <= column)
      throw input_error(model_.config, "person class " + std::to_string(options_.person_class) +
                                           " but the model has " + std::to_string(out.cols - 5) + " classes");
    for (int r = 0; r < out.rows; ++r) {
      const float* row = out.ptr<float>(r);
      const float score = row[column];
      if (!(score >= options_.confidence) || score <= 0.0f) continue;
      const PersonBox b = make_box(row[0] * image.width, row[1] * image.height, row[2] * image.width,
                                   row[3] * image.height, score, image);
      if (b.box.width > 0 && b.box.height > 0) raw.push_back(b);
    }
  }
}

void DarknetDetector::decode_onnx(const std::vector<cv::Mat>& outputs, cv::Size image,
                                  std::vector<PersonBox>& raw) const {
  if (outputs.size() != 1 || outputs[0].dims != 3 || outputs[0].size[0] != 1)
    throw input_error(model_.config, "expected one ONNX output of shape 1 x N x (5 + classes)");
  const cv::Mat& out = outputs[0];
  const int rows = out.size[1];
  const int cols = out.size[2];
  const int column = 5 + options_.person_class;
  if (cols <= column) throw input_error(model_.config, "person class out of range of the ONNX output");
  const cv::Mat table(rows, cols, CV_32F, const_cast<float*>(out.ptr<float>()));
  const float sx = static_cast<float>(image.width) / options_.input_size;
  const float sy = static_cast<float>(image.height) / options_.input_size;
  for (int r = 0; r < rows; ++r) {
    const float* row = table.ptr<float>(r);
    const float score = row[4] * row[column];
    if (!(score >= options_.confidence) || score <= 0.0f) continue;
    const PersonBox b = make_box(row[0] * sx, row[1] * sy, row[2] * sx, row[3] * sy, score, image);
    if (b.box.width > 0 && b.box.height > 0) raw.push_back(b);
  }
}

}  // namespace crowdslam::people
