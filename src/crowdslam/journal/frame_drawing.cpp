#include "crowdslam/journal/frame_drawing.h"

#include <opencv2/imgproc.hpp>

#include "crowdslam/system/system.h"

namespace crowdslam::journal {

FrameDrawing FrameDrawing::from(const system::FrameReport& r) {
  FrameDrawing d;
  d.boxes.reserve(r.boxes.size());
  for (const auto& b : r.boxes) d.boxes.push_back(b.box);
  d.kept.reserve(r.kept_keypoints.size());
  for (const auto& k : r.kept_keypoints) d.kept.push_back(k.pt);
  d.removed.reserve(r.removed_keypoints.size());
  for (const auto& k : r.removed_keypoints) d.removed.push_back(k.pt);
  d.status = "frame " + std::to_string(r.index) + "  boxes " + std::to_string(r.person_boxes) + "  kept " +
             std::to_string(r.kept_keypoints.size()) + "  removed " + std::to_string(r.removed_keypoints.size()) +
             "  budget " + std::to_string(r.feature_budget) + "  " + tracking::to_string(r.state);
  return d;
}

cv::Mat FrameDrawing::draw(const cv::Mat& colour) const {
  cv::Mat canvas;
  if (colour.channels() == 1) {
    cv::cvtColor(colour, canvas, cv::COLOR_GRAY2BGR);
  } else {
    canvas = colour.clone();
  }
  for (const auto& b : boxes) cv::rectangle(canvas, cv::Rect(b), cv::Scalar(255, 80, 0), 2);
  for (const auto& p : kept) cv::circle(canvas, p, 3, cv::Scalar(0, 200, 0), 1);
  for (const auto& p : removed) cv::circle(canvas, p, 3, cv::Scalar(0, 0, 255), 1);
  cv::putText(canvas, status, cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 2);
  cv::putText(canvas, status, cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1);
  return canvas;
}

}  // namespace crowdslam::journal
