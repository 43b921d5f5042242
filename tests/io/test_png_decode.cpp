// Fast PNG decoding (io/png_decode.h): the same pixels and type as cv::imdecode for every case it takes,
// cv::imdecode for the rest, and corrupt image data an InputError naming the file.
#include <gtest/gtest.h>
#include <libdeflate.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <thread>
#include <vector>

#include "crowdslam/io/image_check.h"
#include "crowdslam/io/png_decode.h"
#include "test_support.h"

namespace crowdslam::io {
namespace {

namespace fs = std::filesystem;
using test::error_of;
using Bytes = std::vector<unsigned char>;

using test::read_bytes;
using test::write_bytes;

std::uint32_t be32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}

void put_be32(Bytes& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<unsigned char>(v >> shift));
}

struct Chunk {
  std::string type;
  Bytes data;
};

std::vector<Chunk> chunks_of(const Bytes& png) {
  std::vector<Chunk> chunks;
  for (std::size_t pos = 8; pos + 12 <= png.size();) {
    const std::uint32_t length = be32(&png[pos]);
    chunks.push_back({std::string(png.begin() + pos + 4, png.begin() + pos + 8),
                      Bytes(png.begin() + pos + 8, png.begin() + pos + 8 + length)});
    pos += 12 + length;
  }
  return chunks;
}

// A PNG file with correct lengths and CRCs.
Bytes png_of(const std::vector<Chunk>& chunks) {
  Bytes png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  for (const Chunk& chunk : chunks) {
    put_be32(png, static_cast<std::uint32_t>(chunk.data.size()));
    Bytes typed(chunk.type.begin(), chunk.type.end());
    typed.insert(typed.end(), chunk.data.begin(), chunk.data.end());
    png.insert(png.end(), typed.begin(), typed.end());
    put_be32(png, libdeflate_crc32(0, typed.data(), typed.size()));
  }
  return png;
}

Bytes deflate_zlib(const Bytes& raw) {
  libdeflate_compressor* compressor = libdeflate_alloc_compressor(6);
  Bytes out(libdeflate_zlib_compress_bound(compressor, raw.size()));
  out.resize(libdeflate_zlib_compress(compressor, raw.data(), raw.size(), out.data(), out.size()));
  libdeflate_free_compressor(compressor);
  return out;
}

int channels_of(int colour_type) {
  return colour_type == 0 || colour_type == 3 ? 1 : colour_type == 4 ? 2 : colour_type == 2 ? 3 : 4;
}

// Bytes per row of a non-interlaced PNG's filtered image data, filter type byte included.
std::size_t row_bytes(const Bytes& png) {
  const unsigned char* ihdr = png.data() + 16;
  return 1 + (std::size_t{be32(ihdr)} * channels_of(ihdr[9]) * ihdr[8] + 7) / 8;
}

// The filtered image data (filter type byte + row, for each row) of a non-interlaced PNG.
Bytes inflate_idat(const Bytes& png) {
  Bytes z;
  for (const Chunk& chunk : chunks_of(png))
    if (chunk.type == "IDAT") z.insert(z.end(), chunk.data.begin(), chunk.data.end());
  Bytes raw(row_bytes(png) * be32(png.data() + 20));
  libdeflate_decompressor* d = libdeflate_alloc_decompressor();
  const libdeflate_result result =
      libdeflate_zlib_decompress(d, z.data(), z.size(), raw.data(), raw.size(), nullptr);
  libdeflate_free_decompressor(d);
  EXPECT_EQ(result, LIBDEFLATE_SUCCESS);
  return raw;
}

// The same file with its image data replaced by `zlib` (one IDAT chunk).
Bytes with_idat(const Bytes& png, const Bytes& zlib) {
  std::vector<Chunk> chunks;
  for (Chunk& chunk : chunks_of(png)) {
    if (chunk.type == "IDAT") continue;
    chunks.push_back(std::move(chunk));
    if (chunks.size() == 1) chunks.push_back({"IDAT", zlib});  // right after IHDR
  }
  return png_of(chunks);
}

// Counts the filter types of a non-interlaced PNG's rows into `counts`.
void count_filters(const Bytes& png, std::array<int, 5>& counts) {
  const Bytes raw = inflate_idat(png);
  for (std::size_t pos = 0; pos < raw.size(); pos += row_bytes(png)) {
    ASSERT_LE(raw[pos], 4);
    ++counts[raw[pos]];
  }
}

// A PNG made by hand: IHDR, `extra` chunks, IDAT with random "filtered" data (any bytes are valid
// filtered data) whose row filter types cycle through 0..4, IEND. Interlaced images get the Adam7 passes.
Bytes random_png(int width, int height, int bit_depth, int colour_type, std::uint64_t seed,
                 const std::vector<Chunk>& extra = {}, bool interlaced = false) {
  cv::RNG rng(seed);
  const int bits_per_pixel = channels_of(colour_type) * bit_depth;
  Bytes raw;
  int row_number = 0;
  auto add_rows = [&](int w, int h) {
    if (w <= 0 || h <= 0) return;
    for (int y = 0; y < h; ++y) {
      raw.push_back(static_cast<unsigned char>(row_number++ % 5));
      for (int i = 0; i < (w * bits_per_pixel + 7) / 8; ++i)
        raw.push_back(static_cast<unsigned char>(rng.uniform(0, 256)));
    }
  };
  if (!interlaced) {
    add_rows(width, height);
  } else {
    const int start_x[] = {0, 4, 0, 2, 0, 1, 0}, start_y[] = {0, 0, 4, 0, 2, 0, 1};
    const int step_x[] = {8, 8, 4, 4, 2, 2, 1}, step_y[] = {8, 8, 8, 4, 4, 2, 2};
    for (int p = 0; p < 7; ++p)
      add_rows((width - start_x[p] + step_x[p] - 1) / step_x[p],
               (height - start_y[p] + step_y[p] - 1) / step_y[p]);
  }
  Bytes ihdr;
  put_be32(ihdr, static_cast<std::uint32_t>(width));
  put_be32(ihdr, static_cast<std::uint32_t>(height));
  ihdr.insert(ihdr.end(), {static_cast<unsigned char>(bit_depth), static_cast<unsigned char>(colour_type), 0,
                           0, static_cast<unsigned char>(interlaced ? 1 : 0)});
  std::vector<Chunk> chunks = {{"IHDR", ihdr}};
  chunks.insert(chunks.end(), extra.begin(), extra.end());
  chunks.push_back({"IDAT", deflate_zlib(raw)});
  chunks.push_back({"IEND", {}});
  return png_of(chunks);
}

double max_difference(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return 1e9;
  return a.empty() ? 0.0 : cv::norm(a, b, cv::NORM_INF);
}

// decode_png takes the fast path and gives cv::imdecode's pixels and type for both flags.
void expect_fast_and_identical(const Bytes& png, const std::string& what) {
  for (const int flags : {cv::IMREAD_UNCHANGED, cv::IMREAD_ANYCOLOR}) {
    const cv::Mat reference = cv::imdecode(png, flags);
    ASSERT_FALSE(reference.empty()) << what;
    const cv::Mat ours = decode_png(png.data(), png.size(), flags, what);
    ASSERT_FALSE(ours.empty()) << what << " flags " << flags << ": not decoded on the fast path";
    EXPECT_EQ(ours.type(), reference.type()) << what << " flags " << flags;
    EXPECT_EQ(max_difference(ours, reference), 0.0) << what << " flags " << flags;
  }
}

TEST(PngDecodeFast, PaethPredictorBreaksTiesAsTheSpecification) {
  for (int a = 0; a < 256; ++a) {
    for (int b = 0; b < 256; ++b) {
      for (int c = 0; c < 256; ++c) {
        const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
        const int expected = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
        ASSERT_EQ(paeth_predictor(a, b, c), expected) << a << " " << b << " " << c;
      }
    }
  }
}

// Images written by cv::imwrite (libpng's own filter choice) of several types, sizes and levels.
cv::Mat test_image(int kind, cv::Size size, cv::RNG& rng) {
  const int types[] = {CV_16UC1, CV_16UC1, CV_16UC1, CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC3, CV_16UC4};
  cv::Mat image(size, types[kind]);
  const int channels = image.channels();
  const bool sixteen = image.depth() == CV_16U;
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width * channels; ++x) {
      const int ch = x % channels, px = x / channels;
      double v = 0;
      if (kind == 0)
        v = rng.uniform(0, 65536);  // noise
      else if (kind == 1)
        v = 700.0 * px + 301.0 * y + 2.5 * px * y;  // smooth, wide range
      else if (kind == 2)
        v = ((px / 5 + y / 3) % 4 == 0) ? 0 : 4000 + 9 * px + 5 * y + rng.uniform(0, 3);  // depth
      else
        v = (40.0 * ch + 3.0 * px + 2.0 * y + rng.uniform(0, 8)) * (sixteen ? 157 : 1);  // texture
      const int max = sixteen ? 65535 : 255;
      const int value = static_cast<int>(v) % (max + 1);
      if (sixteen)
        image.ptr<std::uint16_t>(y)[x] = static_cast<std::uint16_t>(value);
      else
        image.ptr<unsigned char>(y)[x] = static_cast<unsigned char>(value);
    }
  }
  return image;
}

TEST(PngDecodeFast, ImwriteImagesDecodeAsImdecodeWithAllFilterTypes) {
  test::TempDir dir;
  cv::RNG rng(2024);
  std::array<int, 5> filters{};
  const cv::Size sizes[] = {{1, 1}, {1, 9}, {9, 1}, {7, 5}, {33, 17}, {101, 40}};
  int files = 0;
  for (int kind = 0; kind < 8; ++kind) {
    for (const cv::Size size : sizes) {
      const cv::Mat image = test_image(kind, size, rng);
      for (const int level : {0, 1, 3, 9}) {
        const fs::path path = dir / ("k" + std::to_string(kind) + "_" + std::to_string(size.width) + "x" +
                                     std::to_string(size.height) + "_l" + std::to_string(level) + ".png");
        ASSERT_TRUE(cv::imwrite(path.string(), image, {cv::IMWRITE_PNG_COMPRESSION, level}));
        const Bytes png = read_bytes(path);
        expect_fast_and_identical(png, path.string());
        EXPECT_EQ(
            max_difference(read_colour_image(path.string()), cv::imread(path.string(), cv::IMREAD_ANYCOLOR)),
            0.0)
            << path;
        if (image.type() == CV_16UC1) {
          EXPECT_EQ(max_difference(read_depth_image(path.string()), image), 0.0) << path;
        }
        count_filters(png, filters);
        ++files;
      }
    }
  }
  EXPECT_EQ(files, 8 * 6 * 4);
  for (int f = 0; f < 5; ++f) EXPECT_GT(filters[f], 0) << "no row with filter type " << f << " was tested";
}

// Random filtered data with every filter type, for every colour type and bit depth the fast path takes
// (grey+alpha cannot be written by cv::imwrite).
TEST(PngDecodeFast, EveryFilterColourTypeAndDepthDecodesAsImdecode) {
  std::uint64_t seed = 1;
  for (const int colour_type : {0, 2, 4, 6})
    for (const int bit_depth : {8, 16})
      for (const cv::Size size : {cv::Size(1, 1), cv::Size(1, 12), cv::Size(13, 11), cv::Size(64, 20)})
        expect_fast_and_identical(random_png(size.width, size.height, bit_depth, colour_type, seed++),
                                  "type " + std::to_string(colour_type) + " depth " +
                                      std::to_string(bit_depth) + " " + std::to_string(size.width) + "x" +
                                      std::to_string(size.height));
}

TEST(PngDecodeFast, AncillaryChunksThatOpenCvIgnoresKeepTheFastPath) {
  const Bytes text = {'C', 'o', 'm', 'm', 'e', 'n', 't', 0, 'h', 'i'};
  const std::vector<Chunk> extra = {
      {"gAMA", {0, 0, 0xB1, 0x8F}}, {"sRGB", {0}}, {"tEXt", text}, {"pHYs", Bytes(9, 1)}};
  expect_fast_and_identical(random_png(20, 9, 16, 0, 7, extra), "16-bit grey with gAMA, sRGB, tEXt, pHYs");
  expect_fast_and_identical(random_png(20, 9, 8, 2, 8, extra), "RGB with gAMA, sRGB, tEXt, pHYs");
}

// What the fast path leaves to cv::imdecode still decodes, and exactly as before.
TEST(PngDecodeFast, OtherPngsFallBackToImdecode) {
  test::TempDir dir;
  Bytes palette(3 * 256);
  for (std::size_t i = 0; i < palette.size(); ++i) palette[i] = static_cast<unsigned char>(i * 37);
  const Bytes exif = {'I', 'I', 0x2A, 0, 8, 0, 0, 0, 1, 0, 0x12, 0x01, 3,
                      0,   1,   0,    0, 0, 6, 0, 0, 0, 0, 0,    0,    0};
  const std::vector<std::pair<std::string, Bytes>> cases = {
      {"interlaced grey16", random_png(21, 13, 16, 0, 3, {}, true)},
      {"interlaced rgb8", random_png(10, 17, 8, 2, 4, {}, true)},
      {"palette", random_png(15, 6, 8, 3, 5, {{"PLTE", palette}})},
      {"grey 4-bit", random_png(15, 6, 4, 0, 6)},
      {"grey with tRNS", random_png(15, 6, 8, 0, 7, {{"tRNS", {0, 9}}})},
      {"rgb with tRNS", random_png(15, 6, 8, 2, 8, {{"tRNS", {0, 9, 0, 9, 0, 9}}})},
      {"rgb with eXIf", random_png(15, 6, 8, 2, 9, {{"eXIf", exif}})},
  };
  for (const auto& [what, png] : cases) {
    for (const int flags : {cv::IMREAD_UNCHANGED, cv::IMREAD_ANYCOLOR})
      EXPECT_TRUE(decode_png(png.data(), png.size(), flags, what).empty()) << what << " flags " << flags;
    const fs::path path = dir / "fallback.png";
    write_bytes(path, png);
    const cv::Mat reference = cv::imdecode(png, cv::IMREAD_ANYCOLOR);
    ASSERT_FALSE(reference.empty()) << what;
    EXPECT_EQ(max_difference(read_colour_image(path.string()), reference), 0.0) << what;
    if (what == "interlaced grey16") {
      EXPECT_EQ(max_difference(read_depth_image(path.string()), cv::imdecode(png, cv::IMREAD_UNCHANGED)),
                0.0);
    }
  }
}

TEST(PngDecodeFast, OnlyUnchangedAndAnyColourFlagsAreHandled) {
  const Bytes png = random_png(15, 6, 16, 2, 10);
  for (const int flags : {int{cv::IMREAD_COLOR}, int{cv::IMREAD_GRAYSCALE}, int{cv::IMREAD_ANYDEPTH},
                          cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR})
    EXPECT_TRUE(decode_png(png.data(), png.size(), flags, "rgb16").empty()) << flags;
}

// Blank images compress close to deflate's limit (1032:1); the early "too little data" check must
// not refuse them. Sides up to 65536 take the fast path, wider ones are left to cv::imdecode.
TEST(PngDecodeFast, BlankImagesAndSideLimits) {
  test::TempDir dir;
  const std::vector<std::pair<cv::Mat, bool>> cases = {{cv::Mat::zeros(480, 640, CV_16UC1), true},
                                                       {cv::Mat::zeros(2, 65536, CV_8UC1), true},
                                                       {cv::Mat::zeros(2, 65537, CV_8UC1), false}};
  for (const auto& [image, fast] : cases) {
    const fs::path path = dir / "blank.png";
    ASSERT_TRUE(cv::imwrite(path.string(), image, {cv::IMWRITE_PNG_COMPRESSION, 9}));
    const Bytes png = read_bytes(path);
    EXPECT_EQ(decode_png(png.data(), png.size(), cv::IMREAD_UNCHANGED, "blank").empty(), !fast) << image.cols;
    EXPECT_EQ(
        max_difference(read_colour_image(path.string()), cv::imread(path.string(), cv::IMREAD_ANYCOLOR)), 0.0)
        << image.cols;
  }
}

TEST(PngDecodeFast, ThreadsDecodeConcurrently) {
  const Bytes a = random_png(200, 100, 16, 0, 11), b = random_png(150, 90, 8, 2, 12);
  const cv::Mat ref_a = cv::imdecode(a, cv::IMREAD_UNCHANGED), ref_b = cv::imdecode(b, cv::IMREAD_UNCHANGED);
  std::array<int, 2> mismatches{};
  std::vector<std::thread> threads;
  for (int t = 0; t < 2; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < 50; ++i) {
        const Bytes& png = (i + t) % 2 ? a : b;
        const cv::Mat& ref = (i + t) % 2 ? ref_a : ref_b;
        if (max_difference(decode_png(png.data(), png.size(), cv::IMREAD_UNCHANGED, "t"), ref) != 0)
          ++mismatches[t];
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  EXPECT_EQ(mismatches[0] + mismatches[1], 0);
}

// Real dataset files: the first PNGs of a shared folder, byte for byte as cv::imread.
void expect_folder_as_imread(const fs::path& folder, std::size_t count, bool depth) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder))
    if (entry.path().extension() == ".png") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  files.resize(std::min(files.size(), count));
  ASSERT_FALSE(files.empty()) << folder;
  for (const fs::path& file : files) {
    expect_fast_and_identical(read_bytes(file), file.string());
    const cv::Mat ours = depth ? read_depth_image(file.string()) : read_colour_image(file.string());
    const cv::Mat reference = cv::imread(file.string(), depth ? cv::IMREAD_UNCHANGED : cv::IMREAD_ANYCOLOR);
    EXPECT_EQ(max_difference(ours, reference), 0.0) << file;
  }
}

TEST(PngDecodeFast, BonnDepthFramesAsImread) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  expect_folder_as_imread(test::shared_data("bonn_crowd") / "depth", 20, true);
}

TEST(PngDecodeFast, KittiGreyFramesAsImread) {
  CROWDSLAM_REQUIRE_SHARED("kitti07_head");
  expect_folder_as_imread(test::shared_data("kitti07_head") / "image_0", 3, false);
}

// Corrupt image data whose chunk CRCs are right (so only decoding can tell).
class PngDecodeFastErrors : public testing::Test {
 protected:
  test::TempDir dir_;
  const fs::path path_ = dir_ / "depth.png";
  const Bytes png_ = random_png(80, 60, 16, 0, 99);
  const Bytes raw_ = inflate_idat(png_);

  std::string error_for(const Bytes& png) {
    write_bytes(path_, png);
    testing::internal::CaptureStderr();
    const std::string message = error_of([&] { (void)read_depth_image(path_.string()); });
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
    EXPECT_NE(message.find(path_.string() + ": corrupt PNG image ("), std::string::npos) << message;
    return message;
  }
};

TEST_F(PngDecodeFastErrors, DamagedCompressedDataIsAnError) {
  Bytes z = deflate_zlib(raw_);
  for (std::size_t i = z.size() / 2; i < z.size() / 2 + 8; ++i) z[i] ^= 0x5A;
  const std::string message = error_for(with_idat(png_, z));
  EXPECT_EQ(message.find("CRC"), std::string::npos) << message;  // the chunk CRCs were right
}

TEST_F(PngDecodeFastErrors, CompressedDataCutShortIsAnError) {
  Bytes z = deflate_zlib(raw_);
  z.resize(z.size() / 2);
  error_for(with_idat(png_, z));
}

TEST_F(PngDecodeFastErrors, FilterTypeAbove4IsAnError) {
  Bytes raw = raw_;
  raw[3 * (1 + 80 * 2)] = 7;  // row 3
  const std::string message = error_for(with_idat(png_, deflate_zlib(raw)));
  EXPECT_NE(message.find("row 3 has filter type 7"), std::string::npos) << message;
}

TEST_F(PngDecodeFastErrors, TooLittleImageDataIsAnErrorTooMuchIsLeftToLibpng) {
  const Bytes short_raw(raw_.begin(), raw_.end() - 7);
  EXPECT_NE(error_for(with_idat(png_, deflate_zlib(short_raw))).find("too little image data"),
            std::string::npos);
  // More than the image: libpng warns and decodes it, so the fast path hands it over (empty result) and
  // the reading functions give cv::imdecode's image, as they did before the fast path.
  Bytes long_raw = raw_;
  long_raw.push_back(0);
  Bytes trailing = deflate_zlib(raw_);
  trailing.insert(trailing.end(), {1, 2, 3});
  for (const Bytes& png : {with_idat(png_, deflate_zlib(long_raw)), with_idat(png_, trailing)}) {
    EXPECT_TRUE(decode_png(png.data(), png.size(), cv::IMREAD_UNCHANGED, "x.png").empty());
    const cv::Mat expected = cv::imdecode(png, cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(expected.empty());
    write_bytes(path_, png);
    const cv::Mat got = read_depth_image(path_.string());
    ASSERT_EQ(got.type(), expected.type());
    EXPECT_EQ(cv::norm(got, expected, cv::NORM_INF), 0.0);
  }
}

TEST_F(PngDecodeFastErrors, HugeSizeWithLittleDataIsRefusedBeforeAllocating) {
  std::vector<Chunk> chunks = chunks_of(random_png(1, 1, 16, 0, 5));
  Bytes& ihdr = chunks[0].data;
  ihdr[2] = 0xEA, ihdr[3] = 0x60, ihdr[6] = 0x0F, ihdr[7] = 0xA0;  // 60000 x 4000: 480 MB, in 13 bytes
  EXPECT_NE(error_for(png_of(chunks)).find("too little image data"), std::string::npos);
}

}  // namespace
}  // namespace crowdslam::io
