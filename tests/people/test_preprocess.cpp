// Network input preparation: letterbox / stretch transforms in closed form, pad value, channel order and
// normalisation of each preset, and the exact inverse mapping of boxes.
#include <gtest/gtest.h>

#include <opencv2/dnn.hpp>

#include "crowdslam/people/detector.h"
#include "crowdslam/people/dnn_detector.h"
#include "crowdslam/people/preprocess.h"
#include "crowdslam/util/error.h"
#include "test_support.h"

namespace crowdslam::people {
namespace {

// Network blob value at channel c, row y, column x (1 x 3 x H x W).
float at(const cv::Mat& blob, int c, int y, int x) { return blob.ptr<float>(0, c)[y * blob.size[3] + x]; }

TEST(InputTransform, LetterboxIsTopLeftAnchoredWithTruncatedSize) {
  // 640 x 480 into 416 x 256: r = min(416 / 640, 256 / 480) = 0.5333 (height limits);
  // width int(640 r) = 341 (341.33 truncated), height 256.
  const InputTransform t = make_input_transform({640, 480}, {416, 256}, ResizeMode::kLetterbox);
  EXPECT_EQ(t.resized, cv::Size(341, 256));
  EXPECT_DOUBLE_EQ(t.scale_x, 341.0 / 640.0);
  EXPECT_DOUBLE_EQ(t.scale_y, 256.0 / 480.0);
  // Width limits: 768 x 576 into 320 x 320 -> 320 x 240.
  const InputTransform w = make_input_transform({768, 576}, {320, 320}, ResizeMode::kLetterbox);
  EXPECT_EQ(w.resized, cv::Size(320, 240));
  EXPECT_DOUBLE_EQ(w.scale_x, 320.0 / 768.0);
  // 480 * (256 / 480) must not come out as 255 (integer arithmetic).
  EXPECT_EQ(make_input_transform({853, 480}, {416, 256}, ResizeMode::kLetterbox).resized, cv::Size(416, 234));
  EXPECT_EQ(make_input_transform({100, 480}, {416, 256}, ResizeMode::kLetterbox).resized, cv::Size(53, 256));
  // Stretch: each axis on its own.
  const InputTransform s = make_input_transform({640, 480}, {160, 160}, ResizeMode::kStretch);
  EXPECT_EQ(s.resized, cv::Size(160, 160));
  EXPECT_DOUBLE_EQ(s.scale_x, 0.25);
  EXPECT_DOUBLE_EQ(s.scale_y, 1.0 / 3.0);
}

TEST(InputTransform, BoxesMapThereAndBackExactly) {
  const InputTransform t = make_input_transform({640, 480}, {416, 256}, ResizeMode::kLetterbox);
  const cv::Rect2f image_box(120, 60, 240, 300);
  const cv::Rect2f net = t.to_network(image_box);
  EXPECT_FLOAT_EQ(net.x, 120.0f * 341 / 640);  // 63.9375
  EXPECT_FLOAT_EQ(net.y, 32.0f);
  EXPECT_FLOAT_EQ(net.width, 127.875f);
  EXPECT_FLOAT_EQ(net.height, 160.0f);
  const cv::Rect2f back = t.to_image(net);
  EXPECT_NEAR(back.x, 120, 1e-4);
  EXPECT_NEAR(back.y, 60, 1e-4);
  EXPECT_NEAR(back.width, 240, 1e-4);
  EXPECT_NEAR(back.height, 300, 1e-4);
  // Darknet fractions of the input: for a stretch the factor is the image size itself.
  const InputTransform s = make_input_transform({640, 480}, {320, 256}, ResizeMode::kStretch);
  EXPECT_EQ(s.image_per_fraction_x(), 640.0);
  EXPECT_EQ(s.image_per_fraction_y(), 480.0);
  EXPECT_DOUBLE_EQ(t.image_per_fraction_x(), 416.0 * 640 / 341);
}

// A synthetic 640 x 480 image, background BGR (10, 20, 30), with a known block BGR (200, 100, 50) at
// x 120..360, y 60..360: after the letterbox the block sits where the transform says, and the padding
// (x >= 341) has the pad value, in each preset's channel order and normalisation.
cv::Mat synthetic_image() {
  cv::Mat image(480, 640, CV_8UC3, cv::Scalar(10, 20, 30));
  image(cv::Rect(120, 60, 240, 300)).setTo(cv::Scalar(200, 100, 50));
  return image;
}

TEST(Preprocess, YoloxLetterboxKeepsBgrRawValuesAndPads114) {
  const Preprocessing pre = preprocessing_preset("yolox");
  EXPECT_FALSE(pre.rgb);
  EXPECT_EQ(pre.resize, ResizeMode::kLetterbox);
  InputTransform t;
  const cv::Mat blob = make_input_blob(synthetic_image(), {416, 256}, pre, &t);
  ASSERT_EQ(blob.size[1], 3);
  ASSERT_EQ(blob.size[2], 256);
  ASSERT_EQ(blob.size[3], 416);
  // The block's centre (240, 210) maps to (127.9, 112).
  const cv::Rect2f block = t.to_network({120, 60, 240, 300});
  const int bx = static_cast<int>(block.x + block.width / 2), by = static_cast<int>(block.y + block.height / 2);
  EXPECT_FLOAT_EQ(at(blob, 0, by, bx), 200.0f);  // B first, unscaled
  EXPECT_FLOAT_EQ(at(blob, 1, by, bx), 100.0f);
  EXPECT_FLOAT_EQ(at(blob, 2, by, bx), 50.0f);
  // Background inside the image area, the padding right of it, at the bottom-right corner.
  EXPECT_FLOAT_EQ(at(blob, 0, 5, 5), 10.0f);
  for (int c = 0; c < 3; ++c) {
    EXPECT_FLOAT_EQ(at(blob, c, 100, 341), 114.0f) << c;
    EXPECT_FLOAT_EQ(at(blob, c, 255, 415), 114.0f) << c;
  }
  EXPECT_FLOAT_EQ(at(blob, 0, 100, 340), 10.0f);  // the last image column
}

TEST(Preprocess, ByteTrackIsRgbOver255WithImageNetNormalisationAfterPadding) {
  const Preprocessing pre = preprocessing_preset("bytetrack");
  InputTransform t;
  const cv::Mat blob = make_input_blob(synthetic_image(), {416, 256}, pre, &t);
  const double mean[3] = {0.485, 0.456, 0.406}, std[3] = {0.229, 0.224, 0.225};
  const double block_rgb[3] = {50, 100, 200}, background_rgb[3] = {30, 20, 10};
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(at(blob, c, 112, 127), (block_rgb[c] / 255 - mean[c]) / std[c], 1e-5) << c;
    EXPECT_NEAR(at(blob, c, 5, 5), (background_rgb[c] / 255 - mean[c]) / std[c], 1e-5) << c;
    // Padded with 114 before the normalisation.
    EXPECT_NEAR(at(blob, c, 100, 400), (114.0 / 255 - mean[c]) / std[c], 1e-5) << c;
  }
  EXPECT_NEAR(at(blob, 0, 100, 400), (114.0 / 255 - 0.485) / 0.229, 1e-5);  // = -0.1227
}

TEST(Preprocess, DarknetStretchIsTheFormerBlobFromImageExactly) {
  const cv::Mat image = synthetic_image();
  for (const cv::Size input : {cv::Size(160, 160), cv::Size(320, 256)}) {
    const cv::Mat blob = make_input_blob(image, input, preprocessing_preset("darknet"));
    const cv::Mat former = cv::dnn::blobFromImage(image, 1.0 / 255.0, input, cv::Scalar(), true, false);
    ASSERT_EQ(blob.total(), former.total());
    EXPECT_EQ(cv::norm(blob, former, cv::NORM_INF), 0.0);
  }
}

TEST(Preprocess, UnknownNamesAreErrorsNamingKeyAndValue) {
  EXPECT_NE(test::error_of([] { (void)preprocessing_preset("imagenet"); }).find("Detector.preprocess"),
            std::string::npos);
  EXPECT_NE(test::error_of([] { (void)preprocessing_preset("imagenet", "--preprocess"); }).find("imagenet"),
            std::string::npos);
  EXPECT_NE(test::error_of([] { (void)parse_resize_mode("crop"); }).find("\"crop\""), std::string::npos);
  Preprocessing bad = preprocessing_preset("bytetrack");
  bad.std[1] = 0;
  EXPECT_NE(test::error_of([&] { bad.check(); }).find("std[1]"), std::string::npos);
}

TEST(InputSize, ParsesWidthByHeightAndSquareAndNamesBadValues) {
  EXPECT_EQ(parse_input_size("416x256", "--input"), cv::Size(416, 256));
  EXPECT_EQ(parse_input_size("320", "--input"), cv::Size(320, 320));
  for (const char* bad : {"416x250", "0x256", "416x", "x256", "big", "416x256x3", "4096x256", "-32", ""}) {
    const std::string message = test::error_of([&] { (void)parse_input_size(bad, "--input"); });
    EXPECT_NE(message.find("--input"), std::string::npos) << bad;
    EXPECT_NE(message.find(std::string("\"") + bad + "\""), std::string::npos) << message;
  }
  EXPECT_EQ(input_size_text({416, 256}), "416x256");
  EXPECT_EQ(input_size_text({160, 160}), "160");
  DetectorOptions o;
  EXPECT_EQ(o.input(), cv::Size(160, 160));
  o.input_width = 416;
  o.input_height = 256;
  EXPECT_EQ(o.input(), cv::Size(416, 256));
  EXPECT_NO_THROW(o.check());
  o.input_height = 0;
  EXPECT_NE(test::error_of([&] { o.check(); }).find("input_width / input_height"), std::string::npos);
  o.input_height = 250;
  EXPECT_NE(test::error_of([&] { o.check(); }).find("input_height"), std::string::npos);
}

// Darknet candidates (fractions of a stretched input) come back as the former detector computed them:
// cx * image width - (w * image width) / 2, then clip_box, bit for bit.
TEST(ToImageBoxes, DarknetStretchIsTheFormerArithmetic) {
  const InputTransform t = make_input_transform({640, 480}, {160, 160}, ResizeMode::kStretch);
  const CentreBox c{0.3137f, 0.5521f, 0.1234f, 0.4321f, 0.7f};
  const std::vector<PersonBox> boxes = to_image_boxes({c}, Backend::kDarknet, t);
  ASSERT_EQ(boxes.size(), 1u);
  const float cx = c.cx * 640, cy = c.cy * 480, w = c.w * 640, h = c.h * 480;
  const cv::Rect2f former = clip_box(cv::Rect2f(cx - w / 2, cy - h / 2, w, h), 640, 480);
  EXPECT_EQ(boxes[0].box.x, former.x);
  EXPECT_EQ(boxes[0].box.y, former.y);
  EXPECT_EQ(boxes[0].box.width, former.width);
  EXPECT_EQ(boxes[0].box.height, former.height);
  EXPECT_NEAR(former.x, 0.3137 * 640 - 0.1234 * 640 / 2, 1e-3);
  EXPECT_EQ(boxes[0].confidence, 0.7f);
  // A box entirely in the letterbox padding is dropped; one crossing the image edge is clipped.
  const InputTransform l = make_input_transform({640, 480}, {416, 256}, ResizeMode::kLetterbox);
  EXPECT_TRUE(to_image_boxes({{380, 100, 40, 40, 0.9f}}, Backend::kYolox, l).empty());
  const auto clipped = to_image_boxes({{341, 128, 40, 40, 0.9f}}, Backend::kYolox, l);
  ASSERT_EQ(clipped.size(), 1u);
  EXPECT_NEAR(clipped[0].box.x, 321.0 * 640 / 341, 1e-3);
  EXPECT_FLOAT_EQ(clipped[0].box.x + clipped[0].box.width, 640.0f);
}

}  // namespace
}  // namespace crowdslam::people
