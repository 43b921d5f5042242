#include "crowdslam/io/png_decode.h"

#include <libdeflate.h>

#include <cstdint>
#include <cstring>
#include <memory>
#include <new>
#include <opencv2/imgcodecs.hpp>
#include <type_traits>
#include <vector>

#include "crowdslam/io/input_text.h"
#include "crowdslam/util/error.h"

namespace crowdslam::io {
namespace {

constexpr std::size_t kSignatureBytes = 8;
constexpr std::uint32_t kMaxSide = 1u << 16;                // wider or taller: left to cv::imdecode
constexpr std::size_t kMaxRawBytes = std::size_t{1} << 30;  // filtered image data; more: cv::imdecode
// Deflate cannot expand data more than 1032:1 (a 258-byte match in 2 bits); image data needing more
// than this (with a margin) is cut short, and is refused before its buffer is allocated.
constexpr std::size_t kMaxInflateRatio = 1100;
// Per-thread buffers larger than this are freed after each image rather than kept for the next one.
constexpr std::size_t kKeepScratchBytes = std::size_t{64} << 20;

bool chunk_is(const unsigned char* type, const char* name) { return std::memcmp(type, name, 4) == 0; }

// What decoding needs from the chunks.
struct PngLayout {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  int bit_depth = 0;
  int colour_type = 0;
  std::size_t first_idat = 0;  // offset of the first IDAT chunk (they are consecutive)
  std::size_t idat_chunks = 0;
  std::size_t idat_bytes = 0;
};

// Walks the chunks; false when the file is not one decode_png handles (cv::imdecode decides).
bool read_layout(const unsigned char* data, std::size_t size, PngLayout& png) {
  std::size_t pos = kSignatureBytes;
  bool idat_ended = false;
  while (pos + 12 <= size) {
    const std::uint32_t length = load_be32(data + pos);
    const unsigned char* type = data + pos + 4;
    const unsigned char* body = data + pos + 8;
    if (length > size - pos - 12) return false;
    if (pos == kSignatureBytes) {
      if (!chunk_is(type, "IHDR") || length != 13) return false;
      png.width = load_be32(body);
      png.height = load_be32(body + 4);
      png.bit_depth = body[8];
      png.colour_type = body[9];
      const bool plain = body[10] == 0 && body[11] == 0 && body[12] == 0;  // deflate, filter 0, no interlace
      const bool sample = png.bit_depth == 8 || png.bit_depth == 16;
      const bool colour =
          png.colour_type == 0 || png.colour_type == 2 || png.colour_type == 4 || png.colour_type == 6;
      const bool side_ok = png.width > 0 && png.height > 0 && png.width <= kMaxSide && png.height <= kMaxSide;
      if (!plain || !sample || !colour || !side_ok) return false;
    } else if (chunk_is(type, "IDAT")) {
      if (idat_ended) return false;  // IDAT chunks must be consecutive: libpng reports it
      if (png.idat_chunks++ == 0) png.first_idat = pos;
      png.idat_bytes += length;
    } else {
      if (png.idat_chunks > 0) idat_ended = true;
      if (chunk_is(type, "IEND")) return png.idat_chunks > 0;
      // Transparency makes OpenCV add alpha, eXIf makes it rotate; other critical chunks (PLTE or
      // unknown ones) are libpng's business. Other ancillary chunks (gAMA, sRGB, pHYs, text, ...) do
      // not change what OpenCV's reader returns.
      if (chunk_is(type, "tRNS") || chunk_is(type, "eXIf") || (type[0] & 0x20) == 0) return false;
    }
    pos += 12 + std::size_t{length};
  }
  return false;
}

// Per reader thread: the libdeflate decompressor and buffers, reused from image to image.
class Scratch {
 public:
  Scratch() = default;
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;
  ~Scratch() { libdeflate_free_decompressor(inflater_); }

  libdeflate_decompressor* inflater() {
    if (inflater_ == nullptr) inflater_ = libdeflate_alloc_decompressor();
    if (inflater_ == nullptr) throw std::bad_alloc();
    return inflater_;
  }
  unsigned char* raw(std::size_t bytes) {
    if (bytes > raw_capacity_) {
      raw_.reset();
      raw_capacity_ = 0;
      raw_.reset(new unsigned char[bytes]);  // not zeroed: inflating overwrites it
      raw_capacity_ = bytes;
    }
    return raw_.get();
  }
  std::vector<unsigned char>& idat() { return idat_; }
  const unsigned char* zeros(std::size_t bytes) {
    if (zeros_.size() < bytes) zeros_.resize(bytes, 0);
    return zeros_.data();
  }
  void trim() {
    if (raw_capacity_ > kKeepScratchBytes) {
      raw_.reset();
      raw_capacity_ = 0;
    }
    if (idat_.capacity() > kKeepScratchBytes) std::vector<unsigned char>().swap(idat_);
    idat_.clear();
  }

 private:
  libdeflate_decompressor* inflater_ = nullptr;
  std::unique_ptr<unsigned char[]> raw_;
  std::size_t raw_capacity_ = 0;
  std::vector<unsigned char> idat_;
  std::vector<unsigned char> zeros_;  // the row above the first row
};

// Freed when the thread exits.
Scratch& thread_scratch() {
  thread_local Scratch scratch;
  return scratch;
}

// Trims the thread's scratch buffers when decoding ends (also by an exception).
struct TrimOnExit {
  Scratch& scratch;
  ~TrimOnExit() { scratch.trim(); }
};

// Undoes one row's filter in place. `cur` and `prev` are the row and the row above (already unfiltered;
// zeros for the first row), `n` bytes each, Bpp bytes per pixel. The left neighbours are carried in
// registers (a, c), not reloaded from the row just written.
template <int Bpp>
void unfilter_row(unsigned filter, unsigned char* __restrict cur, const unsigned char* __restrict prev,
                  std::size_t n) {
  switch (filter) {
    case 1: {  // Sub
      unsigned char a[Bpp] = {};
      for (std::size_t i = 0; i < n; i += Bpp)
        for (int k = 0; k < Bpp; ++k) a[k] = cur[i + k] = static_cast<unsigned char>(cur[i + k] + a[k]);
      break;
    }
    case 2:  // Up
      for (std::size_t i = 0; i < n; ++i) cur[i] = static_cast<unsigned char>(cur[i] + prev[i]);
      break;
    case 3: {  // Average
      unsigned a[Bpp] = {};
      for (std::size_t i = 0; i < n; i += Bpp) {
        for (int k = 0; k < Bpp; ++k) {
          a[k] = static_cast<unsigned char>(cur[i + k] + ((a[k] + prev[i + k]) >> 1));
          cur[i + k] = static_cast<unsigned char>(a[k]);
        }
      }
      break;
    }
    case 4: {  // Paeth
      int a[Bpp] = {};
      int c[Bpp] = {};
      for (std::size_t i = 0; i < n; i += Bpp) {
        for (int k = 0; k < Bpp; ++k) {
          const int b = prev[i + k];
          a[k] = static_cast<unsigned char>(cur[i + k] + paeth_predictor(a[k], b, c[k]));
          cur[i + k] = static_cast<unsigned char>(a[k]);
          c[k] = b;
        }
      }
      break;
    }
    default:  // None (types above 4 are refused before)
      break;
  }
}

using Unfilter = void (*)(unsigned, unsigned char*, const unsigned char*, std::size_t);

Unfilter unfilter_for(int bytes_per_pixel) {
  switch (bytes_per_pixel) {
    case 1:
      return &unfilter_row<1>;
    case 2:
      return &unfilter_row<2>;
    case 3:
      return &unfilter_row<3>;
    case 4:
      return &unfilter_row<4>;
    case 6:
      return &unfilter_row<6>;
    default:
      return &unfilter_row<8>;
  }
}

// Which input channel feeds output channel `out` (OpenCV's order: B, G, R, A; grey copied to B, G, R).
constexpr int source_channel(int channels_in, int out) {
  if (channels_in == 1) return 0;
  if (channels_in == 2) return out < 3 ? 0 : 1;
  return out < 3 ? 2 - out : 3;
}

// One unfiltered row (big-endian samples, PNG channel order) into one row of the cv::Mat.
template <int ChannelsIn, int ChannelsOut, bool In16, bool Out16>
void convert_row(const unsigned char* __restrict in, unsigned char* __restrict out_row, int width) {
  static_assert(In16 || !Out16);
  constexpr int kInBytes = In16 ? 2 : 1;
  if constexpr (ChannelsIn == 1 && ChannelsOut == 1 && !In16) {
    std::memcpy(out_row, in, static_cast<std::size_t>(width));
  } else {
    using Out = std::conditional_t<Out16, std::uint16_t, unsigned char>;
    Out* out = reinterpret_cast<Out*>(out_row);
    for (int x = 0; x < width; ++x) {
      const unsigned char* pixel = in + static_cast<std::size_t>(x) * ChannelsIn * kInBytes;
      for (int ch = 0; ch < ChannelsOut; ++ch) {
        const unsigned char* s = pixel + source_channel(ChannelsIn, ch) * kInBytes;
        // 16 -> 8 bits keeps the high byte, as libpng's png_set_strip_16 (OpenCV's reader) does.
        out[x * ChannelsOut + ch] = Out16 ? static_cast<Out>((s[0] << 8) | s[1]) : static_cast<Out>(s[0]);
      }
    }
  }
}

using RowConverter = void (*)(const unsigned char*, unsigned char*, int);

struct Conversion {
  int type;
  RowConverter convert;
};

// cv::imdecode's output for PNG: IMREAD_UNCHANGED keeps the depth and alpha (grey+alpha becomes BGRA);
// IMREAD_ANYCOLOR gives 8 bits, one channel for grey and three (BGR) for the rest.
template <int ChannelsIn, bool In16>
Conversion conversion(bool unchanged) {
  constexpr int kKept = ChannelsIn == 1 ? 1 : ChannelsIn == 3 ? 3 : 4;
  constexpr int kColour = ChannelsIn == 1 ? 1 : 3;
  if (unchanged)
    return {CV_MAKETYPE(In16 ? CV_16U : CV_8U, kKept), &convert_row<ChannelsIn, kKept, In16, In16>};
  return {CV_8UC(kColour), &convert_row<ChannelsIn, kColour, In16, false>};
}

int channels_of(int colour_type) {
  switch (colour_type) {
    case 0:
      return 1;
    case 4:
      return 2;
    case 2:
      return 3;
    default:
      return 4;
  }
}

Conversion conversion_for(int channels, bool sixteen, bool unchanged) {
  switch (channels) {
    case 1:
      return sixteen ? conversion<1, true>(unchanged) : conversion<1, false>(unchanged);
    case 2:
      return sixteen ? conversion<2, true>(unchanged) : conversion<2, false>(unchanged);
    case 3:
      return sixteen ? conversion<3, true>(unchanged) : conversion<3, false>(unchanged);
    default:
      return sixteen ? conversion<4, true>(unchanged) : conversion<4, false>(unchanged);
  }
}

[[noreturn]] void corrupt(const std::string& path, const std::string& what) {
  throw input_error(clip_text(path), "corrupt PNG image (" + what + ")");
}

// Inflates all IDAT data into `raw` (exactly raw_size bytes); throws when it does not inflate or is short.
// False when it holds more than the image (more rows, or bytes after the zlib stream): libpng only warns
// about those and decodes the image, so the caller leaves such a file to cv::imdecode, as before.
bool inflate_image_data(const unsigned char* data, const PngLayout& png, Scratch& scratch, unsigned char* raw,
                        std::size_t raw_size, const std::string& path) {
  const unsigned char* in = data + png.first_idat + 8;
  if (png.idat_chunks > 1) {
    std::vector<unsigned char>& joined = scratch.idat();
    joined.resize(png.idat_bytes);
    std::size_t pos = png.first_idat;
    for (std::size_t i = 0, at = 0; i < png.idat_chunks; ++i) {
      const std::size_t length = load_be32(data + pos);
      if (length > 0) std::memcpy(joined.data() + at, data + pos + 8, length);
      at += length;
      pos += 12 + length;
    }
    in = joined.data();
  }
  std::size_t in_used = 0;
  std::size_t out_size = 0;
  const libdeflate_result result = libdeflate_zlib_decompress_ex(scratch.inflater(), in, png.idat_bytes, raw,
                                                                 raw_size, &in_used, &out_size);
  if (result == LIBDEFLATE_SUCCESS && out_size == raw_size && in_used == png.idat_bytes) return true;
  const std::string expected = std::to_string(raw_size) + " bytes for " + std::to_string(png.width) + "x" +
                               std::to_string(png.height) + " pixels";
  if (result == LIBDEFLATE_BAD_DATA)
    corrupt(path, "image data does not inflate: damaged deflate stream or Adler-32 mismatch");
  if (result == LIBDEFLATE_INSUFFICIENT_SPACE) return false;  // more than the image's rows
  if (result != LIBDEFLATE_SUCCESS)
    corrupt(path, "image data does not inflate (libdeflate error " + std::to_string(result) + ")");
  if (out_size != raw_size)
    corrupt(path, "too little image data: " + std::to_string(out_size) + " of " + expected);
  return false;  // bytes after the end of the zlib stream
}

}  // namespace

cv::Mat decode_png(const unsigned char* data, std::size_t size, int flags, const std::string& path) {
  if (flags != cv::IMREAD_UNCHANGED && flags != cv::IMREAD_ANYCOLOR) return {};
  PngLayout png;
  if (!read_layout(data, size, png)) return {};
  const int channels = channels_of(png.colour_type);
  const int bytes_per_pixel = channels * png.bit_depth / 8;
  const std::size_t row_bytes = std::size_t{png.width} * static_cast<std::size_t>(bytes_per_pixel);
  const std::size_t raw_size = (row_bytes + 1) * png.height;
  if (raw_size > kMaxRawBytes) return {};
  if (raw_size / kMaxInflateRatio > png.idat_bytes + 64)
    corrupt(path, "too little image data: " + std::to_string(png.idat_bytes) + " compressed bytes for " +
                      std::to_string(png.width) + "x" + std::to_string(png.height) + " pixels");

  Scratch& scratch = thread_scratch();
  const TrimOnExit trim{scratch};
  unsigned char* raw = scratch.raw(raw_size);
  if (!inflate_image_data(data, png, scratch, raw, raw_size, path)) return {};

  const Conversion to_mat = conversion_for(channels, png.bit_depth == 16, flags == cv::IMREAD_UNCHANGED);
  const Unfilter unfilter = unfilter_for(bytes_per_pixel);
  cv::Mat image(static_cast<int>(png.height), static_cast<int>(png.width), to_mat.type);
  const unsigned char* prev = scratch.zeros(row_bytes);
  for (int y = 0; y < image.rows; ++y) {
    unsigned char* row = raw + static_cast<std::size_t>(y) * (row_bytes + 1);
    const unsigned filter = row[0];
    if (filter > 4)
      corrupt(path,
              "row " + std::to_string(y) + " has filter type " + std::to_string(filter) + " (valid: 0 to 4)");
    unfilter(filter, row + 1, prev, row_bytes);
    to_mat.convert(row + 1, image.ptr(y), image.cols);
    prev = row + 1;
  }
  return image;
}

}  // namespace crowdslam::io
