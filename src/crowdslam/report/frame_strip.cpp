#include "crowdslam/report/frame_strip.h"

#include <spdlog/spdlog.h>

#include <opencv2/imgproc.hpp>

#include "crowdslam/io/image_check.h"
#include "crowdslam/io/jpeg_encode.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::report {

void FrameStripOptions::check() const {
  if (width_px < 16 || width_px > 4096) {
    throw InputError("report: frame width must be 16..4096 px, got " + std::to_string(width_px));
  }
  if (jpeg_quality < 1 || jpeg_quality > 100) {
    throw InputError("report: JPEG quality must be 1..100, got " + std::to_string(jpeg_quality));
  }
}

std::vector<size_t> spread_indices(size_t available, size_t count) {
  std::vector<size_t> indices;
  if (available == 0 || count == 0) return indices;
  if (available <= count) {
    for (size_t i = 0; i < available; ++i) indices.push_back(i);
    return indices;
  }
  if (count == 1) return {0};
  for (size_t i = 0; i < count; ++i) indices.push_back(i * (available - 1) / (count - 1));
  return indices;
}

std::string base64_encode(const unsigned char* data, size_t size) {
  static const char* const kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < size; i += 3) {
    const unsigned v = (unsigned{data[i]} << 16) | (unsigned{data[i + 1]} << 8) | data[i + 2];
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  if (i + 1 == size) {
    const unsigned v = unsigned{data[i]} << 16;
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += "==";
  } else if (i + 2 == size) {
    const unsigned v = (unsigned{data[i]} << 16) | (unsigned{data[i + 1]} << 8);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += '=';
  }
  return out;
}

std::vector<EmbeddedFrame> embed_frames(const std::vector<std::filesystem::path>& files,
                                        const FrameStripOptions& options) {
  options.check();
  std::vector<EmbeddedFrame> frames;
  for (const size_t i : spread_indices(files.size(), options.max_frames)) {
    const auto& file = files[i];
    cv::Mat image;
    try {
      image = io::read_bgr_image(file.string());
    } catch (const std::exception& e) {
      spdlog::warn("report: {}: not a readable image, left out of the strip ({})", clip_text(file.string()),
                   e.what());
      continue;
    }
    if (image.cols > options.width_px) {
      const int height = std::max(1, image.rows * options.width_px / image.cols);
      cv::Mat small;
      cv::resize(image, small, cv::Size(options.width_px, height), 0, 0, cv::INTER_AREA);
      image = small;
    }
    const std::vector<unsigned char> jpeg = io::encode_jpeg(image, options.jpeg_quality);
    EmbeddedFrame frame;
    frame.frame_index = parse_int(file.stem().string()).value_or(-1);
    frame.data_url = "data:image/jpeg;base64," + base64_encode(jpeg.data(), jpeg.size());
    frames.push_back(std::move(frame));
  }
  return frames;
}

}  // namespace crowdslam::report
