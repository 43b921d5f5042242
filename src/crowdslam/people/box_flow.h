#pragma once
// Moves person boxes with the image motion between two frames (Lucas-Kanade optical flow on a few corners
// inside each box), so frames the detector did not see still get boxes where the people are now.
//
// Each FlowBox carries its own corners (positions in the frame it was last moved to). move_boxes() tracks
// every box's corners with one pyramidal LK call from `from` to `to`, keeps the corners that pass a
// forward-backward check, and moves the box by their median displacement and scales it about its centre
// by the median ratio of corner distances (the Median Flow tracker's estimate, Kalal et al. 2010). A box
// with fewer than `min_points` surviving corners keeps its place and size (it is reported as not moved):
// a person on a textureless background gives LK nothing to track, and a box that stays is safer for the
// filter than one that jumps.
#include <cstddef>
#include <opencv2/core.hpp>
#include <vector>

#include "crowdslam/people/detector.h"

namespace crowdslam::people {

struct FlowBox {
  PersonBox box;
  std::vector<cv::Point2f> points;  // corners inside the box, in the frame the box is in
  int track_id = -1;                // BoxTracker's id (-1: not tracked)
};

struct BoxFlowOptions {
  int max_points_per_box = 24;   // corners seeded per box (cv::goodFeaturesToTrack)
  int min_points = 4;            // fewer surviving corners: the box is not moved
  double forward_backward_px = 1.5;  // a corner is kept when tracking it back lands this close to its start
  int window = 21;               // LK window (pixels) and pyramid levels
  int levels = 3;
  void check() const;            // throws InputError naming the bad value
};

// A grey frame with its LK pyramid, built once and reused by every move from or to that frame.
struct FlowImage {
  cv::Mat gray;
  std::vector<cv::Mat> pyramid;
  [[nodiscard]] bool empty() const { return gray.empty(); }
};
FlowImage make_flow_image(const cv::Mat& gray, const BoxFlowOptions& options);

// How one box moved: its centre by (dx, dy), its size by `scale` about its centre.
struct BoxMotion {
  bool moved = false;     // false: kept in place (too few corners) or left the image
  bool left_image = false;
  double dx = 0;
  double dy = 0;
  double scale = 1.0;
};

// The same motion applied to another box (a raw box that follows the NMS box that suppressed it):
// translated by (dx, dy) and scaled by `scale` about the leader's centre `leader_centre` (before the
// move), clipped to the image. Returns an empty box when it left the image.
cv::Rect2f follow_motion(const cv::Rect2f& box, const cv::Point2f& leader_centre, const BoxMotion& motion,
                         int width, int height);

struct FlowStats {
  std::size_t boxes_moved = 0;   // boxes moved by their corners' flow
  std::size_t boxes_kept = 0;    // boxes left in place (too few corners survived)
};

// Seeds corners inside each box (replacing their points) from `gray` (8-bit, one channel).
void seed_points(const cv::Mat& gray, std::vector<FlowBox>& boxes, const BoxFlowOptions& options);

// Moves the boxes from frame `from` to frame `to` (both 8-bit grey, same size). Boxes are clipped to the
// image; a box that leaves it entirely is removed. Points are updated to their positions in `to`.
FlowStats move_boxes(const cv::Mat& from, const cv::Mat& to, std::vector<FlowBox>& boxes,
                     const BoxFlowOptions& options);
// The same with prebuilt pyramids; `motions` (optional) gets one entry per input box, in input order.
FlowStats move_boxes(const FlowImage& from, const FlowImage& to, std::vector<FlowBox>& boxes,
                     const BoxFlowOptions& options, std::vector<BoxMotion>* motions = nullptr);

std::vector<FlowBox> to_flow_boxes(const std::vector<PersonBox>& boxes);
std::vector<PersonBox> to_person_boxes(const std::vector<FlowBox>& boxes);

}  // namespace crowdslam::people
