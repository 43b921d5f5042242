#pragma once
// What --save-frames draws on a frame: person boxes (blue), kept keypoints (green), keypoints removed by
// the people filter (red) and a status line. A copy of what it needs, so it can be drawn on another thread.
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "crowdslam/people/detector.h"

namespace crowdslam::system {
struct FrameReport;
}

namespace crowdslam::journal {

struct FrameDrawing {
  std::vector<cv::Rect2f> boxes;
  std::vector<cv::Point2f> kept;
  std::vector<cv::Point2f> removed;
  std::string status;

  static FrameDrawing from(const system::FrameReport& report);
  // A BGR copy of `colour` (grey is converted) with the drawing on it.
  [[nodiscard]] cv::Mat draw(const cv::Mat& colour) const;
};

}  // namespace crowdslam::journal
