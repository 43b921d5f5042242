// io::encode_jpeg against OpenCV's decoder: what it writes decodes to the image within JPEG's loss, and
// bad input is an error, not a crash.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "crowdslam/io/jpeg_encode.h"
#include "crowdslam/util/error.h"

namespace crowdslam::io {
namespace {

cv::Mat gradient_bgr(int width, int height) {
  cv::Mat image(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      image.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uchar>(x * 255 / width), static_cast<uchar>(y * 255 / height),
                                            static_cast<uchar>((x + y) % 256));
  return image;
}

TEST(JpegEncode, ColourDecodesBackWithinJpegLossAndKeepsBgrOrder) {
  const cv::Mat image = gradient_bgr(96, 64);
  const std::vector<unsigned char> jpeg = encode_jpeg(image, 95);
  ASSERT_GE(jpeg.size(), 4u);
  EXPECT_EQ(jpeg[0], 0xFF);
  EXPECT_EQ(jpeg[1], 0xD8);
  const cv::Mat decoded = cv::imdecode(jpeg, cv::IMREAD_COLOR);
  ASSERT_EQ(decoded.size(), image.size());
  EXPECT_GT(cv::PSNR(decoded, image), 30.0);
  // Channel order: blue grows with x, green with y (swapped channels would fail both).
  EXPECT_LT(decoded.at<cv::Vec3b>(32, 2)[0], 20);
  EXPECT_GT(decoded.at<cv::Vec3b>(32, 93)[0], 230);
  EXPECT_LT(decoded.at<cv::Vec3b>(2, 48)[1], 20);
  EXPECT_GT(decoded.at<cv::Vec3b>(61, 48)[1], 230);
}

TEST(JpegEncode, GreyStaysOneChannelAndLowerQualityIsSmaller) {
  cv::Mat grey;
  cv::cvtColor(gradient_bgr(128, 96), grey, cv::COLOR_BGR2GRAY);
  const auto high = encode_jpeg(grey, 95);
  const auto low = encode_jpeg(grey, 20);
  EXPECT_LT(low.size(), high.size());
  const cv::Mat decoded = cv::imdecode(high, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(decoded.type(), CV_8UC1);
  EXPECT_GT(cv::PSNR(decoded, grey), 35.0);
}

TEST(JpegEncode, BadImagesAndQualitiesAreErrors) {
  EXPECT_THROW(encode_jpeg(cv::Mat(), 90), InputError);
  EXPECT_THROW(encode_jpeg(cv::Mat(8, 8, CV_16UC1, cv::Scalar(0)), 90), InputError);
  EXPECT_THROW(encode_jpeg(cv::Mat(8, 8, CV_8UC4, cv::Scalar(0)), 90), InputError);
  EXPECT_THROW(encode_jpeg(cv::Mat(8, 8, CV_8UC1, cv::Scalar(0)), 0), InputError);
  EXPECT_THROW(encode_jpeg(cv::Mat(8, 8, CV_8UC1, cv::Scalar(0)), 101), InputError);
  // A view into a larger image (rows not contiguous) is encoded as the view.
  const cv::Mat big = gradient_bgr(64, 64);
  const cv::Mat decoded = cv::imdecode(encode_jpeg(big(cv::Rect(10, 20, 30, 16)), 95), cv::IMREAD_COLOR);
  ASSERT_EQ(decoded.size(), cv::Size(30, 16));
  EXPECT_GT(cv::PSNR(decoded, big(cv::Rect(10, 20, 30, 16)).clone()), 30.0);
}

}  // namespace
}  // namespace crowdslam::io
