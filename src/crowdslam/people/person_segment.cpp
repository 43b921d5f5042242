#include "crowdslam/people/person_segment.h"

#include <algorithm>
#include <cmath>
#include <deque>

namespace crowdslam::people {

PersonSegment::PersonSegment(const cv::Mat& depth_image_raw, double depth_factor, const cv::Rect2f& box,
                             double person_m, double window_m, const PersonSegmentOptions& options)
    : cell_px_(std::max(1, options.cell_px)) {
  if (depth_image_raw.empty() || depth_image_raw.type() != CV_16UC1 || !(person_m > 0) || !(depth_factor > 0))
    return;
  const cv::Rect area = cv::Rect(cv::Point(cvFloor(box.x), cvFloor(box.y)),
                                 cv::Point(cvCeil(box.x + box.width), cvCeil(box.y + box.height))) &
                        cv::Rect(0, 0, depth_image_raw.cols, depth_image_raw.rows);
  if (area.width < cell_px_ || area.height < cell_px_) return;
  origin_ = area.tl();
  const int cols = area.width / cell_px_;
  const int rows = area.height / cell_px_;
  cv::Mat z(rows, cols, CV_32F);
  for (int r = 0; r < rows; ++r) {
    const auto* row = depth_image_raw.ptr<uint16_t>(origin_.y + r * cell_px_ + cell_px_ / 2);
    for (int c = 0; c < cols; ++c) {
      const uint16_t v = row[origin_.x + c * cell_px_ + cell_px_ / 2];
      const double m = v / depth_factor;
      z.at<float>(r, c) = v > 0 && std::abs(m - person_m) <= window_m ? static_cast<float>(m) : 0.0f;
    }
  }
  in_ = cv::Mat::zeros(rows, cols, CV_8U);
  std::deque<cv::Point> queue;
  // Seeds: the central region (half the width, 70 % of the height, as estimate_person_depth) at the
  // person's depth.
  const int c0 = cols / 4, c1 = cols - cols / 4;
  const int r0 = rows * 15 / 100, r1 = rows - rows * 15 / 100;
  for (int r = r0; r < r1; ++r) {
    for (int c = c0; c < c1; ++c) {
      const float d = z.at<float>(r, c);
      if (d > 0 && d >= person_m - 0.05 && d <= person_m + options.seed_behind_m) {
        in_.at<uint8_t>(r, c) = 1;
        queue.emplace_back(c, r);
      }
    }
  }
  const int dc[4] = {1, -1, 0, 0};
  const int dr[4] = {0, 0, 1, -1};
  while (!queue.empty()) {
    const cv::Point p = queue.front();
    queue.pop_front();
    const float d = z.at<float>(p.y, p.x);
    const double tolerance = std::max(options.step_m, options.step_ratio * d);
    for (int k = 0; k < 4; ++k) {
      const int c = p.x + dc[k], r = p.y + dr[k];
      if (c < 0 || r < 0 || c >= cols || r >= rows || in_.at<uint8_t>(r, c) != 0) continue;
      const float n = z.at<float>(r, c);
      if (n > 0 && std::abs(n - d) <= tolerance) {
        in_.at<uint8_t>(r, c) = 1;
        queue.emplace_back(c, r);
      }
    }
  }
  cells_in_segment_ = cv::countNonZero(in_);
}

bool PersonSegment::near(const cv::Point2f& p, int radius_px) const {
  if (in_.empty()) return false;
  // The cells the square window of half-side radius_px around p overlaps (radius 0: p's own cell).
  auto cell = [this](double v) { return static_cast<int>(std::floor(v / cell_px_)); };
  const int c0 = std::max(0, cell(p.x - radius_px - origin_.x));
  const int c1 = std::min(in_.cols - 1, cell(p.x + radius_px - origin_.x));
  const int r0 = std::max(0, cell(p.y - radius_px - origin_.y));
  const int r1 = std::min(in_.rows - 1, cell(p.y + radius_px - origin_.y));
  for (int r = r0; r <= r1; ++r) {
    const auto* row = in_.ptr<uint8_t>(r);
    for (int c = c0; c <= c1; ++c) {
      if (row[c] != 0) return true;
    }
  }
  return false;
}

}  // namespace crowdslam::people
