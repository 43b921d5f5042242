#pragma once
// Fast PNG decoding for the common cases (internal to io; used by image_check.cpp).
//
// cv::imdecode spends most of a 16-bit depth PNG's time in zlib's inflate and libpng's row unfiltering;
// here the IDAT data is inflated in one call with libdeflate (one decompressor per thread, reused) and the
// rows are unfiltered in place with the predictors kept in registers. Handled: non-interlaced, 8 or 16
// bits per sample, grey, grey+alpha, RGB or RGBA, no tRNS, PLTE or eXIf chunk, no unknown critical chunk,
// width and height at most 65536, and cv::IMREAD_UNCHANGED or cv::IMREAD_ANYCOLOR. Everything else
// (palette, fewer than 8 bits, interlaced, transparency chunk, EXIF orientation, ...) is left to
// cv::imdecode: decode_png returns an empty Mat and the caller falls back.
//
// The result is what cv::imdecode gives with the same flags (byte for byte; the tests check it):
//   IMREAD_UNCHANGED: grey -> CV_8UC1/CV_16UC1, RGB -> BGR, RGBA -> BGRA, grey+alpha -> BGRA (grey
//   copied to B, G and R); 16-bit samples in host byte order.
//   IMREAD_ANYCOLOR: 8-bit (16-bit samples keep their high byte, as libpng's png_set_strip_16), alpha
//   dropped, grey stays one channel, RGB -> BGR, grey+alpha -> 3 channels of grey.
// Image data that inflates to less than the image, or does not inflate, is an error naming the file (as
// with libpng). Image data with more than the image (extra rows, or bytes after the zlib stream) is left to
// cv::imdecode, which decodes it as before (libpng only warns).
#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

namespace crowdslam::io {

// `data` must be a whole PNG file (signature first) whose chunk structure and CRCs have been checked.
// Returns the decoded image, or an empty Mat when the file or `flags` is not one this decoder handles.
// Throws InputError "PATH: corrupt PNG image (...)" for image data that does not inflate (bad deflate
// data, Adler-32 mismatch), inflates to too little, or has a row filter type above 4.
cv::Mat decode_png(const unsigned char* data, std::size_t size, int flags, const std::string& path);

// A big-endian 32-bit value (PNG chunk lengths and IHDR fields).
inline std::uint32_t load_be32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

// The PNG Paeth predictor of a byte from its left (a), upper (b) and upper-left (c) neighbours, without
// branches: a when |p-a| is smallest (p = a + b - c), else b when |p-b| <= |p-c|, else c.
inline int paeth_predictor(int a, int b, int c) {
  const int pa = b > c ? b - c : c - b;                          // |p - a|
  const int pb = a > c ? a - c : c - a;                          // |p - b|
  const int pc = a + b > 2 * c ? a + b - 2 * c : 2 * c - a - b;  // |p - c|
  const int ab = pb < pa ? b : a;                                // a wins ties with b
  const int min_ab = pb < pa ? pb : pa;
  return pc < min_ab ? c : ab;  // a and b win ties with c
}

}  // namespace crowdslam::io
