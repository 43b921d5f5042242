#pragma once
// A person's surface in a dense depth image, grown from their box: the depth-mode filter's test for the
// background close behind a person (keypoint_filter.h). A box holds the person and, beside and behind
// them, whatever the detector's loose box took in: a wall or a plant 0.2-0.5 m behind the person is
// within the filter's depth margin of them, and was removed with them. A person's body is one surface
// whose depth changes smoothly from cell to cell; what stands behind them is separated from it by a
// step in depth. The segment is grown over a grid of 4 x 4 pixel cells (each cell's centre depth) from
// the cells of the box's central region at the person's depth, to 4-connected neighbours within the box
// whose depth differs by at most max(step_m, step_ratio x depth) and stays within `window_m` of the
// person. A floor the person stands on joins the segment at their feet; a wall behind them does not.
#include <opencv2/core.hpp>

namespace crowdslam::people {

struct PersonSegmentOptions {
  int cell_px = 4;
  double step_m = 0.08;         // largest depth step between neighbouring cells of one surface (or:)
  double step_ratio = 0.04;     // ... this share of the depth, where larger
  double seed_behind_m = 0.15;  // seeds: central cells within [person - 0.05 m, person + this]
};

class PersonSegment {
 public:
  // depth_image_raw: CV_16UC1, metres = value / depth_factor, 0 = no measurement. `person_m` is the
  // person's depth (estimate_person_depth), `window_m` how far in front of or behind it the segment may
  // reach. An empty segment when there is no depth.
  PersonSegment(const cv::Mat& depth_image_raw, double depth_factor, const cv::Rect2f& box, double person_m,
                double window_m, const PersonSegmentOptions& options = {});
  // Whether a cell of the segment overlaps the square of half-side `radius_px` around `p` (radius 0: the
  // cell holding `p`).
  [[nodiscard]] bool near(const cv::Point2f& p, int radius_px) const;
  [[nodiscard]] int cells() const { return cells_in_segment_; }

 private:
  int cell_px_ = 4;
  cv::Point origin_;  // image position of cell (0, 0)'s corner
  cv::Mat in_;        // CV_8U per cell: 1 in the segment
  int cells_in_segment_ = 0;
};

}  // namespace crowdslam::people
