#include "crowdslam/people/detector.h"

#include <algorithm>
#include <cmath>
#include <opencv2/dnn.hpp>
#include <sstream>

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

}  // namespace

void DetectorOptions::check() const {
  require(input_size >= 32 && input_size % 32 == 0, "input_size", "a multiple of 32 and >= 32", input_size);
  require(std::isfinite(confidence) && confidence >= 0 && confidence <= 1, "confidence", "in [0, 1]",
          confidence);
  require(std::isfinite(nms) && nms >= 0 && nms <= 1, "nms", "in [0, 1]", nms);
  require(person_class >= 0, "person_class", ">= 0", person_class);
  require(opencv_threads >= 0, "opencv_threads", ">= 0", opencv_threads);
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

}  // namespace crowdslam::people
