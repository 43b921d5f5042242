#include "crowdslam/people/darknet_model.h"

#include <spdlog/spdlog.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::people {
namespace fs = std::filesystem;
namespace {

std::string read_binary(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) throw input_error(path, "cannot read model file");
  return bytes;
}

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

}  // namespace

void check_weights_size(const cv::dnn::Net& net, const std::string& weights) {
  std::ifstream in(weights, std::ios::binary);
  std::int32_t version[3] = {0, 0, 0};
  in.read(reinterpret_cast<char*>(version), sizeof(version));
  if (!in) throw input_error(weights, "model file too short for a Darknet weights header");
  const bool long_seen = version[0] * 10 + version[1] >= 2 && version[0] < 1000 && version[1] < 1000;
  std::uintmax_t floats = 0;
  // Every layer blob except the Region layers' anchors, which come from the cfg.
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

cv::dnn::Net read_darknet(const ModelFiles& model, double confidence) {
  const std::string cfg = cfg_with_threshold(model.config, confidence);
  const std::string weights = read_binary(model.weights);
  return cv::dnn::readNetFromDarknet(cfg.data(), cfg.size(), weights.data(), weights.size());
}

}  // namespace crowdslam::people
