// Decoders on crafted output tensors: YOLOX grid / stride decode in closed form, objectness x class score,
// NMS dedup, the mapping back to the original image, and layout errors.
#include <gtest/gtest.h>

#include <cmath>

#include "crowdslam/people/dnn_detector.h"
#include "crowdslam/people/yolo_decode.h"
#include "test_support.h"

namespace crowdslam::people {
namespace {

// A zero YOLOX output for `input` and `classes` classes (1 x N x (5 + classes)).
cv::Mat yolox_output(cv::Size input, int classes) {
  const int sizes[] = {1, yolox_rows(input), 5 + classes};
  return cv::Mat(3, sizes, CV_32F, cv::Scalar(0));
}

// Row index of grid cell (gx, gy) at `stride`: the strides' grids follow one another, row-major.
int row_of(cv::Size input, int stride, int gx, int gy) {
  int row = 0;
  for (const int s : kYoloxStrides) {
    if (s == stride) return row + gy * (input.width / s) + gx;
    row += (input.width / s) * (input.height / s);
  }
  ADD_FAILURE() << "no stride " << stride;
  return 0;
}

void set_row(cv::Mat& out, int row, float x, float y, float log_w, float log_h, float objectness,
             std::initializer_list<float> classes) {
  float* p = out.ptr<float>(0, row);
  p[0] = x;
  p[1] = y;
  p[2] = log_w;
  p[3] = log_h;
  p[4] = objectness;
  int c = 5;
  for (const float score : classes) p[c++] = score;
}

TEST(YoloxDecode, RowCountIsTheSumOverStrides) {
  EXPECT_EQ(yolox_rows({416, 256}), 52 * 32 + 26 * 16 + 13 * 8);  // 2184, as the shared models give
  EXPECT_EQ(yolox_rows({320, 192}), 1260);
  EXPECT_EQ(yolox_rows({160, 160}), 525);
}

TEST(YoloxDecode, OneAnchorAtAKnownCellGivesTheClosedFormBox) {
  const cv::Size input(256, 256);
  cv::Mat out = yolox_output(input, 1);
  // Stride 32, cell (3, 2), offsets (0.5, 0.5), exp(log 2) * 32 = 64: centre (112, 80), 64 x 64.
  set_row(out, row_of(input, 32, 3, 2), 0.5f, 0.5f, std::log(2.0f), std::log(2.0f), 0.8f, {0.5f});
  // Stride 8, cell (10, 20), offsets (0.25, -0.5), w exp(0) * 8 = 8, h exp(log 4) * 8 = 32.
  set_row(out, row_of(input, 8, 10, 20), 0.25f, -0.5f, 0.0f, std::log(4.0f), 1.0f, {0.9f});
  const std::vector<CentreBox> boxes = decode_yolox({out}, input, {0, 0.3, "m.onnx"});
  ASSERT_EQ(boxes.size(), 2u);
  const CentreBox& a = boxes[1].cx > 100 ? boxes[1] : boxes[0];
  const CentreBox& b = boxes[1].cx > 100 ? boxes[0] : boxes[1];
  EXPECT_FLOAT_EQ(a.cx, 112);
  EXPECT_FLOAT_EQ(a.cy, 80);
  EXPECT_FLOAT_EQ(a.w, 64);
  EXPECT_FLOAT_EQ(a.h, 64);
  EXPECT_FLOAT_EQ(a.score, 0.4f);  // objectness 0.8 x class 0.5
  EXPECT_FLOAT_EQ(b.cx, 82);       // (10 + 0.25) * 8
  EXPECT_FLOAT_EQ(b.cy, 156);      // (20 - 0.5) * 8
  EXPECT_FLOAT_EQ(b.w, 8);
  EXPECT_FLOAT_EQ(b.h, 32);
  EXPECT_FLOAT_EQ(b.score, 0.9f);
  // 512 x 512 image letterboxed into 256 x 256 (factor 0.5): box (80, 48, 64, 64) -> (160, 96, 128, 128).
  const InputTransform t = make_input_transform({512, 512}, input, ResizeMode::kLetterbox);
  const std::vector<PersonBox> image_boxes = to_image_boxes({a}, Backend::kYolox, t);
  ASSERT_EQ(image_boxes.size(), 1u);
  EXPECT_FLOAT_EQ(image_boxes[0].box.x, 160);
  EXPECT_FLOAT_EQ(image_boxes[0].box.y, 96);
  EXPECT_FLOAT_EQ(image_boxes[0].box.width, 128);
  EXPECT_FLOAT_EQ(image_boxes[0].box.height, 128);
}

TEST(YoloxDecode, ScoreIsObjectnessTimesThePersonClass) {
  const cv::Size input(320, 192);
  cv::Mat out = yolox_output(input, 3);
  set_row(out, 0, 0.5f, 0.5f, 0, 0, 0.9f, {0.5f, 0.1f, 0.1f});   // 0.45: kept
  set_row(out, 1, 0.5f, 0.5f, 0, 0, 0.9f, {0.3f, 0.99f, 0.1f});  // 0.27 < 0.3 (a confident "class 1")
  set_row(out, 2, 0.5f, 0.5f, 0, 0, 0.2f, {1.0f, 0.0f, 0.0f});   // 0.2: objectness too low
  const auto person = decode_yolox({out}, input, {0, 0.3, "m.onnx"});
  ASSERT_EQ(person.size(), 1u);
  EXPECT_FLOAT_EQ(person[0].score, 0.45f);
  EXPECT_FLOAT_EQ(person[0].cx, 4.0f);  // cell (0, 0) at stride 8
  // Class 1 as the person class: only row 1 (0.891).
  const auto other = decode_yolox({out}, input, {1, 0.3, "m.onnx"});
  ASSERT_EQ(other.size(), 1u);
  EXPECT_FLOAT_EQ(other[0].score, 0.9f * 0.99f);
  EXPECT_FLOAT_EQ(other[0].cx, 12.0f);  // cell (1, 0)
}

TEST(YoloxDecode, NmsKeepsTheBestOfNeighbouringAnchors) {
  const cv::Size input(416, 256);
  cv::Mat out = yolox_output(input, 1);
  // The same person seen by two neighbouring stride-16 cells (IoU ~0.9) and a second person far away.
  set_row(out, row_of(input, 16, 10, 5), 0.5f, 0.5f, std::log(4.0f), std::log(8.0f), 0.95f, {0.95f});
  set_row(out, row_of(input, 16, 11, 5), -0.4f, 0.5f, std::log(4.2f), std::log(8.0f), 0.8f, {0.8f});
  set_row(out, row_of(input, 16, 20, 5), 0.5f, 0.5f, std::log(2.0f), std::log(4.0f), 0.7f, {0.7f});
  const InputTransform t = make_input_transform({640, 480}, input, ResizeMode::kLetterbox);
  const auto raw = to_image_boxes(decode_yolox({out}, input, {0, 0.25, "m.onnx"}), Backend::kYolox, t);
  ASSERT_EQ(raw.size(), 3u);
  const auto kept = suppress_non_maxima(raw, 0.25, 0.45);
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_FLOAT_EQ(kept[0].confidence, 0.95f * 0.95f);
  EXPECT_FLOAT_EQ(kept[1].confidence, 0.49f);
  // The kept box in original pixels: centre (168, 88), 64 x 128 network pixels, divided by the scales
  // 341 / 640 and 256 / 480.
  EXPECT_NEAR(kept[0].box.x, (168 - 32) * 640.0 / 341, 1e-3);
  EXPECT_NEAR(kept[0].box.y, (88 - 64) * 480.0 / 256, 1e-3);
  EXPECT_NEAR(kept[0].box.width, 64 * 640.0 / 341, 1e-3);
  EXPECT_NEAR(kept[0].box.height, 240.0, 1e-3);
}

// A person box known in original pixels, encoded into the tensor through the transform's inverse,
// comes back in original pixels (letterboxed 768 x 576 PETS frame at 416 x 256: scale 256 / 576).
TEST(YoloxDecode, KnownImageBoxRoundTripsThroughTheTensor) {
  const cv::Size input(416, 256);
  const InputTransform t = make_input_transform({768, 576}, input, ResizeMode::kLetterbox);
  ASSERT_EQ(t.resized, cv::Size(341, 256));
  const cv::Rect2f person(500, 200, 40, 110);
  const cv::Rect2f net = t.to_network(person);
  const int stride = 8;
  const float cx = net.x + net.width / 2, cy = net.y + net.height / 2;
  const int gx = static_cast<int>(cx / stride), gy = static_cast<int>(cy / stride);
  cv::Mat out = yolox_output(input, 1);
  set_row(out, row_of(input, stride, gx, gy), cx / stride - gx, cy / stride - gy, std::log(net.width / stride),
          std::log(net.height / stride), 0.9f, {0.9f});
  const auto boxes = to_image_boxes(decode_yolox({out}, input, {0, 0.5, "m.onnx"}), Backend::kYolox, t);
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_NEAR(boxes[0].box.x, 500, 1e-3);
  EXPECT_NEAR(boxes[0].box.y, 200, 1e-3);
  EXPECT_NEAR(boxes[0].box.width, 40, 1e-3);
  EXPECT_NEAR(boxes[0].box.height, 110, 1e-3);
}

TEST(YoloxDecode, WrongLayoutsNameTheModelAndTheShape) {
  const cv::Size input(416, 256);
  // A YOLOv5-style export has three anchors per cell: 3 x 2184 rows.
  const int v5[] = {1, 3 * 2184, 85};
  const std::string rows =
      test::error_of([&] { (void)decode_yolox({cv::Mat(3, v5, CV_32F, cv::Scalar(0))}, input, {0, 0.3, "v5.onnx"}); });
  EXPECT_NE(rows.find("v5.onnx"), std::string::npos) << rows;
  EXPECT_NE(rows.find("1x6552x85"), std::string::npos) << rows;
  EXPECT_NE(rows.find("expected 2184 rows"), std::string::npos) << rows;
  const std::string two_d =
      test::error_of([&] { (void)decode_yolox({cv::Mat(2184, 85, CV_32F)}, input, {0, 0.3, "flat.onnx"}); });
  EXPECT_NE(two_d.find("flat.onnx"), std::string::npos) << two_d;
  EXPECT_NE(two_d.find("2184x85"), std::string::npos) << two_d;
  const std::string none = test::error_of([&] { (void)decode_yolox({}, input, {0, 0.3, "none.onnx"}); });
  EXPECT_NE(none.find("0 output(s)"), std::string::npos) << none;
  const std::string person =
      test::error_of([&] { (void)decode_yolox({yolox_output(input, 1)}, input, {1, 0.3, "one.onnx"}); });
  EXPECT_NE(person.find("person class 1 but the model has 1 classes"), std::string::npos) << person;
}

TEST(YoloOnnxDecode, DecodedRowsInNetworkPixels) {
  const int sizes[] = {1, 2, 7};
  cv::Mat out(3, sizes, CV_32F, cv::Scalar(0));
  set_row(out, 0, 100, 50, 20, 40, 0.9f, {0.8f, 0.1f});
  set_row(out, 1, 10, 10, 5, 5, 0.3f, {0.5f, 0.9f});
  const auto boxes = decode_yolo_onnx({out}, {0, 0.2, "v5.onnx"});
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_FLOAT_EQ(boxes[0].cx, 100);
  EXPECT_FLOAT_EQ(boxes[0].w, 20);
  EXPECT_FLOAT_EQ(boxes[0].score, 0.72f);
}

TEST(DarknetDecode, PersonColumnAsIsAndClassErrors) {
  cv::Mat out(2, 6, CV_32F, cv::Scalar(0));
  out.at<float>(0, 0) = 0.5f;
  out.at<float>(0, 4) = 0.9f;
  out.at<float>(0, 5) = 0.6f;  // already objectness x class
  out.at<float>(1, 5) = 0.1f;
  const auto boxes = decode_darknet({out}, {0, 0.2, "b.cfg"});
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_FLOAT_EQ(boxes[0].score, 0.6f);
  EXPECT_NE(test::error_of([&] { (void)decode_darknet({out}, {1, 0.2, "b.cfg"}); }).find("b.cfg"),
            std::string::npos);
}

}  // namespace
}  // namespace crowdslam::people
