#include "crowdslam/people/yolo_decode.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "crowdslam/util/error.h"

namespace crowdslam::people {
namespace {

bool passes(float score, const DecodeOptions& o) { return score >= o.confidence && score > 0.0f; }

// The single 1 x N x (5 + C) output of the ONNX backends, as an N x (5 + C) table; `expected` names the
// layout in the error.
cv::Mat single_table(const std::vector<cv::Mat>& outputs, const DecodeOptions& o, const char* expected) {
  if (outputs.size() != 1 || outputs[0].dims != 3 || outputs[0].size[0] != 1 || outputs[0].type() != CV_32F) {
    std::string got = std::to_string(outputs.size()) + " output(s)";
    if (!outputs.empty()) got += ", the first " + shape_text(outputs[0]);
    throw input_error(o.model_file, std::string("expected one ONNX output of shape ") + expected + ", got " + got);
  }
  const cv::Mat& out = outputs[0];
  const int classes = out.size[2] - 5;
  if (o.person_class >= classes)
    throw input_error(o.model_file, "person class " + std::to_string(o.person_class) + " but the model has " +
                                        std::to_string(std::max(classes, 0)) + " classes (output " +
                                        shape_text(out) + ")");
  return cv::Mat(out.size[1], out.size[2], CV_32F, const_cast<float*>(out.ptr<float>()));
}

}  // namespace

std::string shape_text(const cv::Mat& m) {
  if (m.empty()) return "empty";
  std::string text;
  for (int i = 0; i < m.dims; ++i) text += (i ? "x" : "") + std::to_string(m.size[i]);
  return text;
}

int yolox_rows(cv::Size input) {
  int rows = 0;
  for (const int s : kYoloxStrides) rows += (input.width / s) * (input.height / s);
  return rows;
}

std::vector<CentreBox> decode_darknet(const std::vector<cv::Mat>& outputs, const DecodeOptions& o) {
  const int column = 5 + o.person_class;
  std::vector<CentreBox> boxes;
  for (const cv::Mat& out : outputs) {
    if (out.dims != 2 || out.type() != CV_32F)
      throw input_error(o.model_file, "unexpected output layout " + shape_text(out) +
                                          " (a Darknet yolo/region layer gives rows x (5 + classes))");
    if (out.cols <= column)
      throw input_error(o.model_file, "person class " + std::to_string(o.person_class) + " but the model has " +
                                          std::to_string(out.cols - 5) + " classes");
    for (int r = 0; r < out.rows; ++r) {
      const float* row = out.ptr<float>(r);
      if (passes(row[column], o)) boxes.push_back({row[0], row[1], row[2], row[3], row[column]});
    }
  }
  return boxes;
}

std::vector<CentreBox> decode_yolo_onnx(const std::vector<cv::Mat>& outputs, const DecodeOptions& o) {
  const cv::Mat table = single_table(outputs, o, "1 x N x (5 + classes)");
  const int column = 5 + o.person_class;
  std::vector<CentreBox> boxes;
  for (int r = 0; r < table.rows; ++r) {
    const float* row = table.ptr<float>(r);
    const float score = row[4] * row[column];
    if (passes(score, o)) boxes.push_back({row[0], row[1], row[2], row[3], score});
  }
  return boxes;
}

std::vector<CentreBox> decode_yolox(const std::vector<cv::Mat>& outputs, cv::Size input, const DecodeOptions& o) {
  const cv::Mat table = single_table(outputs, o, "1 x N x (5 + classes) (a raw YOLOX head)");
  const int expected = yolox_rows(input);
  if (table.rows != expected)
    throw input_error(o.model_file, "output " + shape_text(outputs[0]) + " is not a YOLOX head for input " +
                                        std::to_string(input.width) + "x" + std::to_string(input.height) +
                                        ": expected " + std::to_string(expected) +
                                        " rows (strides 8, 16, 32); is it another backend's model?");
  const int column = 5 + o.person_class;
  std::vector<CentreBox> boxes;
  int r = 0;
  for (const int stride : kYoloxStrides) {
    const int cols = input.width / stride;
    const int rows = input.height / stride;
    for (int gy = 0; gy < rows; ++gy) {
      for (int gx = 0; gx < cols; ++gx, ++r) {
        const float* row = table.ptr<float>(r);
        const float score = row[4] * row[column];
        if (!passes(score, o)) continue;
        const auto s = static_cast<float>(stride);
        boxes.push_back({(static_cast<float>(gx) + row[0]) * s, (static_cast<float>(gy) + row[1]) * s,
                         std::exp(row[2]) * s, std::exp(row[3]) * s, score});
      }
    }
  }
  return boxes;
}

}  // namespace crowdslam::people
