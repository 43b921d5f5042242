#include "crowdslam/io/image_check.h"

#include <libdeflate.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "crowdslam/io/input_text.h"
#include "crowdslam/io/jpeg_decode.h"
#include "crowdslam/io/opencv_extras.h"
#include "crowdslam/io/png_decode.h"
#include "crowdslam/util/error.h"

namespace crowdslam::io {
namespace fs = std::filesystem;
namespace {

constexpr std::array<unsigned char, 8> kPngSignature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
constexpr std::uintmax_t kMaxImageFileBytes = std::uintmax_t{1} << 30;

// The whole file; InputError naming it when it cannot be read.
std::vector<unsigned char> read_image_bytes(const std::string& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (status.type() == fs::file_type::not_found)
    throw input_error(clip_text(path), "image file does not exist");
  if (ec) throw input_error(clip_text(path), "cannot access image file: " + ec.message());
  if (!fs::is_regular_file(status)) throw input_error(clip_text(path), "image path is not a regular file");
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw input_error(clip_text(path), "cannot read image file size: " + ec.message());
  if (size == 0) throw input_error(clip_text(path), "image file is empty");
  if (size > kMaxImageFileBytes)
    throw input_error(clip_text(path), "image file of " + std::to_string(size) + " bytes is too large");
  std::vector<unsigned char> bytes(static_cast<std::size_t>(size));
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) throw input_error(clip_text(path), "cannot open image file");
  const std::size_t read = std::fread(bytes.data(), 1, bytes.size(), file);
  std::fclose(file);
  if (read != bytes.size()) throw input_error(clip_text(path), "read error (file changed while reading?)");
  return bytes;
}

// CRC-32 (ISO-HDLC, as PNG and zlib). libdeflate's uses carry-less multiplication where the CPU has it:
// about 0.01 ms for a 240 KB KITTI image, 12 times faster than a slice-by-8 table.
std::uint32_t crc32(const unsigned char* p, std::size_t n) { return libdeflate_crc32(0, p, n); }

bool is_chunk_type(const unsigned char* p) {
  for (int i = 0; i < 4; ++i) {
    const bool letter = (p[i] >= 'A' && p[i] <= 'Z') || (p[i] >= 'a' && p[i] <= 'z');
    if (!letter) return false;
  }
  return true;
}

// Walks the chunks from IHDR to IEND checking lengths and CRCs (bytes after IEND are ignored).
void check_png_chunks(const std::vector<unsigned char>& bytes, const std::string& path) {
  std::size_t pos = kPngSignature.size();
  bool first = true;
  while (true) {
    const std::string at = " at byte " + std::to_string(pos);
    if (pos + 12 > bytes.size())
      throw input_error(clip_text(path), "truncated PNG image (ends" + at + " before the IEND chunk)");
    const unsigned char* chunk = bytes.data() + pos;
    const std::uint32_t length = load_be32(chunk);
    if (length > 0x7FFFFFFFu || !is_chunk_type(chunk + 4))
      throw input_error(clip_text(path), "corrupt PNG image (bad chunk header" + at + ")");
    const std::string type(reinterpret_cast<const char*>(chunk + 4), 4);
    if (pos + 12 + length > bytes.size())
      throw input_error(clip_text(path), "truncated PNG image (chunk " + type + at + " is cut off)");
    if (load_be32(chunk + 8 + length) != crc32(chunk + 4, 4 + length))
      throw input_error(clip_text(path), "corrupt PNG image (CRC error in chunk " + type + at + ")");
    if (first && type != "IHDR")
      throw input_error(clip_text(path), "corrupt PNG image (no IHDR chunk first)");
    first = false;
    if (type == "IEND") return;
    pos += 12 + length;
  }
}

cv::Mat decode(const std::string& path, int flags) {
  const std::vector<unsigned char> bytes = read_image_bytes(path);
  if (bytes.size() >= 2 && bytes[0] == 0xFF && bytes[1] == 0xD8)
    return decode_jpeg(bytes.data(), bytes.size(), path);
  const bool is_png = bytes.size() >= kPngSignature.size() &&
                      std::equal(kPngSignature.begin(), kPngSignature.end(), bytes.begin());
  if (is_png) {
    check_png_chunks(bytes, path);
    cv::Mat image = decode_png(bytes.data(), bytes.size(), flags, path);  // the common cases, fast
    if (!image.empty()) return image;
  }
  cv::Mat image;
  try {
    image = opencv_extras().imdecode(bytes, flags);
  } catch (const cv::Exception& e) {
    throw input_error(clip_text(path), std::string("cannot decode image: ") + e.what());
  }
  if (image.empty())
    throw input_error(clip_text(path), "cannot decode image (unknown format or corrupt file)");
  return image;
}

}  // namespace

cv::Mat read_colour_image(const std::string& path) { return decode(path, cv::IMREAD_ANYCOLOR); }

cv::Mat read_bgr_image(const std::string& path) {
  cv::Mat image = decode(path, cv::IMREAD_ANYCOLOR);
  if (image.channels() == 1) cv::cvtColor(image, image, cv::COLOR_GRAY2BGR);
  return image;
}

cv::Mat read_mask_image(const std::string& path) {
  const cv::Mat image = decode(path, cv::IMREAD_UNCHANGED);
  std::vector<cv::Mat> channels;
  cv::split(image, channels);
  cv::Mat mask = cv::Mat::zeros(image.size(), CV_8UC1);
  for (const cv::Mat& channel : channels) mask.setTo(255, channel != 0);
  return mask;
}

cv::Mat read_depth_image(const std::string& path) {
  cv::Mat depth = decode(path, cv::IMREAD_UNCHANGED);
  if (depth.type() != CV_16UC1) {
    throw input_error(clip_text(path), "depth image must be 16-bit single-channel (got " +
                                           std::to_string(depth.channels()) + " channel(s) of " +
                                           std::to_string(8 * static_cast<int>(depth.elemSize1())) + "-bit)");
  }
  return depth;
}

void check_same_size(const cv::Mat& image, const cv::Size& expected, const std::string& path,
                     const std::string& what) {
  if (image.size() == expected) return;
  throw input_error(clip_text(path), what + " is " + std::to_string(image.cols) + "x" +
                                         std::to_string(image.rows) + ", expected " +
                                         std::to_string(expected.width) + "x" +
                                         std::to_string(expected.height));
}

}  // namespace crowdslam::io
