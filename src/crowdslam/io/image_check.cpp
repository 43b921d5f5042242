#include "crowdslam/io/image_check.h"

#include <array>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "crowdslam/util/error.h"

namespace crowdslam::io {
namespace {

constexpr std::array<unsigned char, 8> kPngSignature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
// Length 0, "IEND", CRC of "IEND".
constexpr std::array<unsigned char, 12> kPngEnd{0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xAE, 0x42, 0x60, 0x82};

std::vector<unsigned char> read_bytes(std::ifstream& in, std::streamoff offset, std::size_t count) {
  std::vector<unsigned char> bytes(count);
  in.seekg(offset);
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(count));
  if (!in) throw InputError("read error");
  return bytes;
}

// Last bytes of the file with trailing zero padding removed (some writers pad JPEGs to a block size).
std::vector<unsigned char> tail_without_padding(std::ifstream& in, std::uintmax_t size) {
  const std::size_t count = static_cast<std::size_t>(std::min<std::uintmax_t>(size, 4096));
  auto tail = read_bytes(in, static_cast<std::streamoff>(size - count), count);
  while (!tail.empty() && tail.back() == 0) tail.pop_back();
  return tail;
}

void check_bytes(const std::string& path, std::uintmax_t size) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw input_error(path, "cannot open image file");
  const std::size_t head_count = static_cast<std::size_t>(std::min<std::uintmax_t>(size, 8));
  const auto head = read_bytes(in, 0, head_count);
  const bool is_jpeg = head.size() >= 2 && head[0] == 0xFF && head[1] == 0xD8;
  const bool is_png =
      head.size() == 8 && std::equal(kPngSignature.begin(), kPngSignature.end(), head.begin());
  if (is_jpeg) {
    const auto tail = tail_without_padding(in, size);
    if (tail.size() < 4 || tail[tail.size() - 2] != 0xFF || tail.back() != 0xD9)
      throw input_error(path, "truncated JPEG image (no end-of-image marker FF D9)");
  } else if (is_png) {
    if (size < kPngSignature.size() + kPngEnd.size()) throw input_error(path, "truncated PNG image");
    const auto tail = read_bytes(in, static_cast<std::streamoff>(size - kPngEnd.size()), kPngEnd.size());
    if (!std::equal(kPngEnd.begin(), kPngEnd.end(), tail.begin()))
      throw input_error(path, "truncated PNG image (does not end with the IEND chunk)");
  }
}

cv::Mat decode(const std::string& path, int flags) {
  check_image_file_complete(path);
  cv::Mat image;
  try {
    image = cv::imread(path, flags);
  } catch (const cv::Exception& e) {
    throw input_error(path, std::string("cannot decode image: ") + e.what());
  }
  if (image.empty()) throw input_error(path, "cannot decode image (unknown format or corrupt file)");
  return image;
}

}  // namespace

void check_image_file_complete(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) throw input_error(path, "image file does not exist");
  if (!std::filesystem::is_regular_file(status)) throw input_error(path, "image path is not a regular file");
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw input_error(path, "cannot read image file size");
  if (size == 0) throw input_error(path, "image file is empty");
  try {
    check_bytes(path, size);
  } catch (const InputError& e) {
    const std::string message = e.what();
    if (message.rfind(path, 0) == 0) throw;
    throw input_error(path, message);
  }
}

cv::Mat read_colour_image(const std::string& path) { return decode(path, cv::IMREAD_ANYCOLOR); }

cv::Mat read_depth_image(const std::string& path) {
  cv::Mat depth = decode(path, cv::IMREAD_UNCHANGED);
  if (depth.type() != CV_16UC1) {
    throw input_error(path, "depth image must be 16-bit single-channel (got " +
                                std::to_string(depth.channels()) + " channel(s) of " +
                                std::to_string(8 * static_cast<int>(depth.elemSize1())) + "-bit)");
  }
  return depth;
}

void check_same_size(const cv::Mat& image, const cv::Size& expected, const std::string& path,
                     const std::string& what) {
  if (image.size() == expected) return;
  throw input_error(path, what + " is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                              ", expected " + std::to_string(expected.width) + "x" +
                              std::to_string(expected.height));
}

}  // namespace crowdslam::io
