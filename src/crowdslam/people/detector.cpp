#include "crowdslam/people/detector.h"

#include <algorithm>
#include <cmath>
#include <opencv2/dnn.hpp>
#include <sstream>
#include <string>

#include "crowdslam/util/error.h"

namespace crowdslam::people {
namespace {

template <typename T>
void require(bool ok, const char* key, const char* expected, T value) {
  if (ok) return;
  std::ostringstream message;
  message << "detector option " << key << " must be " << expected << ", got " << value;
  throw InputError(message.str());
}

bool valid_side(int side) { return side >= 32 && side <= kMaxInputSide && side % 32 == 0; }

}  // namespace

cv::Size DetectorOptions::input() const {
  if (input_width > 0 && input_height > 0) return {input_width, input_height};
  return {input_size, input_size};
}

void DetectorOptions::check() const {
  require(input_size >= 32 && input_size % 32 == 0, "input_size", "a multiple of 32 and >= 32", input_size);
  require(input_size <= kMaxInputSide, "input_size", "<= 2048", input_size);
  require((input_width == 0) == (input_height == 0), "input_width / input_height", "both set or both 0",
          std::to_string(input_width) + " / " + std::to_string(input_height));
  if (input_width != 0) {
    require(valid_side(input_width), "input_width", "a multiple of 32 in 32..2048", input_width);
    require(valid_side(input_height), "input_height", "a multiple of 32 in 32..2048", input_height);
  }
  require(std::isfinite(confidence) && confidence >= 0 && confidence <= 1, "confidence", "in [0, 1]",
          confidence);
  require(std::isfinite(nms) && nms >= 0 && nms <= 1, "nms", "in [0, 1]", nms);
  require(person_class >= 0, "person_class", ">= 0", person_class);
  require(opencv_threads >= 0, "opencv_threads", ">= 0", opencv_threads);
}

cv::Size parse_input_size(const std::string& text, const std::string& key) {
  const std::size_t x = text.find('x');
  const auto side = [&](const std::string& part) {
    std::size_t used = 0;
    int value = 0;
    try {
      value = std::stoi(part, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (part.empty() || used != part.size() || !valid_side(value))
      throw InputError(key +
                       ": expected WIDTHxHEIGHT or one SIZE, each a multiple of 32 in 32..2048, got \"" +
                       text + "\"");
    return value;
  };
  if (x == std::string::npos) {
    const int s = side(text);
    return {s, s};
  }
  return {side(text.substr(0, x)), side(text.substr(x + 1))};
}

std::string input_size_text(cv::Size size) {
  if (size.width == size.height) return std::to_string(size.width);
  return std::to_string(size.width) + "x" + std::to_string(size.height);
}

cv::Rect2f clip_box(const cv::Rect2f& box, int width, int height) {
  if (!std::isfinite(box.x) || !std::isfinite(box.y) || !std::isfinite(box.width) ||
      !std::isfinite(box.height))
    return {0.0f, 0.0f, 0.0f, 0.0f};
  const float x0 = std::max(0.0f, box.x);
  const float y0 = std::max(0.0f, box.y);
  const float x1 = std::min(static_cast<float>(width), box.x + box.width);
  const float y1 = std::min(static_cast<float>(height), box.y + box.height);
  if (!(x1 > x0) || !(y1 > y0)) return {0.0f, 0.0f, 0.0f, 0.0f};
  return {x0, y0, x1 - x0, y1 - y0};
}

double box_iou(const cv::Rect2f& a, const cv::Rect2f& b) {
  if (!(a.width > 0 && a.height > 0 && b.width > 0 && b.height > 0)) return 0.0;
  const double ix = std::min<double>(a.x + a.width, b.x + b.width) - std::max<double>(a.x, b.x);
  const double iy = std::min<double>(a.y + a.height, b.y + b.height) - std::max<double>(a.y, b.y);
  if (ix <= 0 || iy <= 0) return 0.0;
  const double inter = ix * iy;
  return inter / (static_cast<double>(a.width) * a.height + static_cast<double>(b.width) * b.height - inter);
}

std::vector<PersonBox> suppress_non_maxima(const std::vector<PersonBox>& boxes, double confidence,
                                           double nms) {
  std::vector<cv::Rect2d> rects;
  std::vector<float> scores;
  rects.reserve(boxes.size());
  scores.reserve(boxes.size());
  for (const PersonBox& b : boxes) {
    rects.emplace_back(b.box.x, b.box.y, b.box.width, b.box.height);
    scores.push_back(b.confidence);
  }
  std::vector<int> keep;
  cv::dnn::NMSBoxes(rects, scores, static_cast<float>(confidence), static_cast<float>(nms), keep);
  std::vector<PersonBox> kept;
  kept.reserve(keep.size());
  for (int i : keep) kept.push_back(boxes[static_cast<std::size_t>(i)]);
  return kept;
}

int most_overlapping(const cv::Rect2f& box, const std::vector<PersonBox>& candidates) {
  double best = 0.0;
  int index = -1;
  for (size_t k = 0; k < candidates.size(); ++k) {
    const double iou = box_iou(box, candidates[k].box);
    if (iou > best) {
      best = iou;
      index = static_cast<int>(k);
    }
  }
  return index;
}

std::vector<PersonBox> raw_boxes_near_leaders(const Detections& detections, double max_area_ratio,
                                              int* dropped) {
  if (dropped != nullptr) *dropped = 0;
  if (!(max_area_ratio > 0)) return detections.raw;
  std::vector<PersonBox> kept;
  kept.reserve(detections.raw.size());
  for (const PersonBox& r : detections.raw) {
    const int leader = most_overlapping(r.box, detections.boxes);
    if (leader >= 0 &&
        r.box.area() <= max_area_ratio * detections.boxes[static_cast<size_t>(leader)].box.area()) {
      kept.push_back(r);
    } else if (dropped != nullptr) {
      ++*dropped;
    }
  }
  return kept;
}

}  // namespace crowdslam::people
