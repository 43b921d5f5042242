// Strict image decoding (io/image_check.h): libjpeg errors and warnings and PNG CRC errors are
// InputErrors naming the file, nothing leaks to stderr, and valid files decode exactly as cv::imread.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "crowdslam/io/image_check.h"
#include "test_support.h"

namespace crowdslam::io {
namespace {

namespace fs = std::filesystem;
using test::error_of;
using Bytes = std::vector<unsigned char>;

using test::read_bytes;
using test::write_bytes;

// A noisy colour JPEG (large entropy-coded segment), as written by OpenCV (quality 95).
fs::path noise_jpeg(const test::TempDir& dir, const std::string& name, int type = CV_8UC3) {
  cv::Mat noise(120, 160, type);
  cv::RNG rng(12345);  // fixed: the same file whatever ran before
  rng.fill(noise, cv::RNG::UNIFORM, 0, 255);
  const fs::path path = dir / name;
  cv::imwrite(path.string(), noise);
  return path;
}

// Offset of the first byte of entropy-coded data (after the SOS segment).
std::size_t scan_start(const Bytes& jpeg) {
  for (std::size_t i = 2; i + 3 < jpeg.size(); ++i)
    if (jpeg[i] == 0xFF && jpeg[i + 1] == 0xDA) return i + 2 + ((jpeg[i + 2] << 8) | jpeg[i + 3]);
  return 0;
}

double max_difference(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return 1e9;
  return cv::norm(a, b, cv::NORM_INF);
}

TEST(JpegDecode, SameAsImreadOnARealBonnFrame) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const fs::path path = test::shared_data("bonn_crowd") / "rgb" / "1548339819.87426.jpg";
  const cv::Mat ours = read_colour_image(path.string());
  const cv::Mat reference = cv::imread(path.string(), cv::IMREAD_ANYCOLOR);
  ASSERT_EQ(ours.type(), CV_8UC3);
  ASSERT_EQ(ours.size(), cv::Size(640, 480));
  EXPECT_LE(max_difference(ours, reference), 1.0);
  EXPECT_EQ(max_difference(ours, reference), 0.0);  // same libjpeg, same settings: identical
}

TEST(JpegDecode, GreyJpegStaysGreyAndEqualsImread) {
  test::TempDir dir;
  const fs::path path = noise_jpeg(dir, "grey.jpg", CV_8UC1);
  const cv::Mat ours = read_colour_image(path.string());
  EXPECT_EQ(ours.type(), CV_8UC1);
  EXPECT_EQ(max_difference(ours, cv::imread(path.string(), cv::IMREAD_ANYCOLOR)), 0.0);
}

TEST(JpegDecode, ExifOrientationIsAppliedAsImreadDoes) {
  test::TempDir dir;
  Bytes jpeg = read_bytes(noise_jpeg(dir, "plain.jpg"));
  // APP1 "Exif" with a little-endian TIFF IFD0 holding one entry: Orientation (0x0112) = 6 (rotate 90 CW).
  const Bytes exif = {'E',  'x',  'i', 'f', 0, 0, 'I', 'I', 0x2A, 0, 8, 0, 0, 0, 1, 0,
                      0x12, 0x01, 3,   0,   1, 0, 0,   0,   6,    0, 0, 0, 0, 0, 0, 0};
  Bytes app1 = {0xFF, 0xE1, 0, static_cast<unsigned char>(exif.size() + 2)};
  app1.insert(app1.end(), exif.begin(), exif.end());
  jpeg.insert(jpeg.begin() + 2, app1.begin(), app1.end());
  const fs::path path = dir / "rotated.jpg";
  write_bytes(path, jpeg);
  const cv::Mat ours = read_colour_image(path.string());
  EXPECT_EQ(ours.size(), cv::Size(120, 160));  // 160x120 stored, shown upright
  EXPECT_EQ(max_difference(ours, cv::imread(path.string(), cv::IMREAD_ANYCOLOR)), 0.0);
}

TEST(JpegDecode, TrailingBytesAfterTheEndMarkerAreAccepted) {
  test::TempDir dir;
  const fs::path original = noise_jpeg(dir, "a.jpg");
  Bytes jpeg = read_bytes(original);
  for (int i = 0; i < 1000; ++i) jpeg.push_back(static_cast<unsigned char>(i * 7));
  const fs::path padded = dir / "padded.jpg";
  write_bytes(padded, jpeg);
  const cv::Mat image = read_colour_image(padded.string());  // used to be "truncated JPEG image"
  EXPECT_EQ(max_difference(image, cv::imread(original.string(), cv::IMREAD_ANYCOLOR)), 0.0);
}

TEST(JpegDecodeErrors, TruncatedJpegThatStillEndsWithTheEndMarkerNamesTheFile) {
  test::TempDir dir;
  Bytes jpeg = read_bytes(noise_jpeg(dir, "a.jpg"));
  jpeg.resize(jpeg.size() / 2);
  jpeg.push_back(0xFF);
  jpeg.push_back(0xD9);
  const fs::path path = dir / "cut.jpg";
  write_bytes(path, jpeg);
  testing::internal::CaptureStderr();
  const std::string message = error_of([&] { (void)read_colour_image(path.string()); });
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(message.find(path.string() + ": corrupt JPEG image: "), std::string::npos) << message;
  EXPECT_NE(message.find("Corrupt JPEG data"), std::string::npos) << message;  // libjpeg's own words
  EXPECT_EQ(err, "");                                                          // and libjpeg printed nothing
}

// JPEG has no checksum: a flipped bit that libjpeg decodes without complaint (Huffman codes often
// resynchronise) cannot be detected. A damaged run of bytes throws the decoder off for good.
TEST(JpegDecodeErrors, FlippedBitsInTheEntropyCodedDataNameTheFile) {
  test::TempDir dir;
  Bytes jpeg = read_bytes(noise_jpeg(dir, "a.jpg"));
  const std::size_t start = scan_start(jpeg);
  ASSERT_GT(start, 0u);
  const std::size_t middle = start + (jpeg.size() - start) / 2;
  for (std::size_t i = middle; i < middle + 64; ++i) jpeg[i] ^= 0x5A;
  const fs::path path = dir / "flipped.jpg";
  write_bytes(path, jpeg);
  ASSERT_FALSE(cv::imread(path.string()).empty());  // cv::imread returns the damaged image
  testing::internal::CaptureStderr();
  const std::string message = error_of([&] { (void)read_colour_image(path.string()); });
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(message.find(path.string() + ": corrupt JPEG image: "), std::string::npos) << message;
  EXPECT_EQ(err, "");
}

TEST(JpegDecodeErrors, JpegCutWithoutEndMarkerIsTruncated) {
  test::TempDir dir;
  const fs::path path = noise_jpeg(dir, "a.jpg");
  fs::resize_file(path, fs::file_size(path) / 2);
  const std::string message = error_of([&] { (void)read_colour_image(path.string()); });
  EXPECT_NE(message.find(path.string() + ": truncated JPEG image"), std::string::npos) << message;
}

TEST(JpegDecodeErrors, GarbageAfterTheStartMarkerIsAnError) {
  test::TempDir dir;
  write_bytes(dir / "bad.jpg", {0xFF, 0xD8, 0xFF, 0x00, 1, 2, 3, 4, 5, 6, 7, 8, 0xFF, 0xD9});
  const std::string message = error_of([&] { (void)read_colour_image((dir / "bad.jpg").string()); });
  EXPECT_NE(message.find((dir / "bad.jpg").string() + ":"), std::string::npos) << message;
}

// A 16-bit depth PNG with noise (so IDAT is large), as the TUM/Bonn depth maps are stored.
fs::path noise_png(const test::TempDir& dir) {
  cv::Mat depth(60, 80, CV_16UC1);
  cv::RNG rng(54321);
  rng.fill(depth, cv::RNG::UNIFORM, 0, 20000);
  const fs::path path = dir / "depth.png";
  cv::imwrite(path.string(), depth);
  return path;
}

// Offset of the first data byte of the IDAT chunk.
std::size_t idat_data(const Bytes& png) {
  for (std::size_t i = 8; i + 8 < png.size(); ++i)
    if (png[i] == 'I' && png[i + 1] == 'D' && png[i + 2] == 'A' && png[i + 3] == 'T') return i + 4;
  return 0;
}

TEST(PngDecode, ValidDepthEqualsImreadAndTrailingBytesAreAccepted) {
  test::TempDir dir;
  const fs::path path = noise_png(dir);
  const cv::Mat reference = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(max_difference(read_depth_image(path.string()), reference), 0.0);
  Bytes png = read_bytes(path);
  png.insert(png.end(), {1, 2, 3});
  write_bytes(dir / "padded.png", png);
  EXPECT_EQ(max_difference(read_depth_image((dir / "padded.png").string()), reference), 0.0);
}

TEST(MaskImage, SixteenBitIdsAndColourMasksAreSetWhereverNonZero) {
  test::TempDir dir;
  // A 16-bit id image as synth's people_mask/ writes it: ids 1 and 300 (both below 256 after an 8-bit
  // reduction, which turned the whole mask to 0).
  cv::Mat ids = cv::Mat::zeros(20, 30, CV_16UC1);
  ids(cv::Rect(2, 3, 4, 5)).setTo(1);
  ids(cv::Rect(20, 10, 6, 2)).setTo(300);
  ASSERT_TRUE(cv::imwrite((dir / "ids.png").string(), ids));
  const cv::Mat mask = read_mask_image((dir / "ids.png").string());
  ASSERT_EQ(mask.type(), CV_8UC1);
  EXPECT_EQ(cv::countNonZero(mask), 4 * 5 + 6 * 2);
  EXPECT_EQ(mask.at<uint8_t>(3, 2), 255);
  EXPECT_EQ(mask.at<uint8_t>(10, 25), 255);
  EXPECT_EQ(mask.at<uint8_t>(0, 0), 0);
  // A colour mask set in one channel only.
  cv::Mat colour = cv::Mat::zeros(20, 30, CV_8UC3);
  colour.at<cv::Vec3b>(7, 8) = cv::Vec3b(0, 0, 9);
  ASSERT_TRUE(cv::imwrite((dir / "colour.png").string(), colour));
  const cv::Mat from_colour = read_mask_image((dir / "colour.png").string());
  EXPECT_EQ(cv::countNonZero(from_colour), 1);
  EXPECT_EQ(from_colour.at<uint8_t>(7, 8), 255);
  const std::string message = error_of([&] { (void)read_mask_image((dir / "missing.png").string()); });
  EXPECT_NE(message.find("missing.png"), std::string::npos) << message;
}

TEST(PngDecodeErrors, FlippedBitIsACrcErrorNamingTheFileWithoutLibpngNoise) {
  test::TempDir dir;
  const fs::path path = noise_png(dir);
  Bytes png = read_bytes(path);
  const std::size_t data = idat_data(png);
  ASSERT_GT(data, 0u);
  png[data + 100] ^= 0x10;
  write_bytes(path, png);
  testing::internal::CaptureStderr();
  const std::string message = error_of([&] { (void)read_depth_image(path.string()); });
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(message.find(path.string() + ": corrupt PNG image (CRC error in chunk IDAT"), std::string::npos)
      << message;
  EXPECT_EQ(err, "");  // cv::imread let libpng print "libpng error: IDAT: CRC error"
}

TEST(PngDecodeErrors, TruncatedPngNamesTheFile) {
  test::TempDir dir;
  const fs::path path = noise_png(dir);
  for (const double fraction : {0.5, 0.999}) {
    Bytes png = read_bytes(noise_png(dir));
    png.resize(static_cast<std::size_t>(fraction * static_cast<double>(png.size())));
    write_bytes(path, png);
    testing::internal::CaptureStderr();
    const std::string message = error_of([&] { (void)read_depth_image(path.string()); });
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
    EXPECT_NE(message.find(path.string() + ": truncated PNG image"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace crowdslam::io
