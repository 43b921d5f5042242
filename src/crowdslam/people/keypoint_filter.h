#pragma once
// The people filter: decides which keypoints to keep given the person boxes of the frame.
//
// Paper mode (Crowd-SLAM): every keypoint inside any box grown by `margin_px` is dropped. Boxes are tested
// directly (no per-pixel mask), so the cost is keypoints x boxes, independent of the image size.
// Depth mode (our extension, RGB-D/stereo): inside a box, only keypoints at the person's depth (or without
// depth) are dropped; background clearly behind the person (by more than `depth_margin_m`) is kept.
// The person's depth is a robust estimate from the depth values in the box's central region. With
// `silhouettes`, a keypoint whose 5 x 5 neighbourhood shows the person's depth (within the margin) is on
// their outline and is dropped too: its descriptor sees the person's edge and moves with them. Background
// within two margins behind the person needs a 17 x 17 neighbourhood clear of the person instead.
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "crowdslam/people/detector.h"

namespace crowdslam::people {

enum class FilterMode { kPaper, kDepth };
FilterMode parse_filter_mode(const std::string& name, const std::string& key);
const char* to_string(FilterMode mode);

struct KeypointFilterOptions {
  FilterMode mode = FilterMode::kPaper;
  double margin_px = 5.0;       // boxes grown by this on every side
  double depth_margin_m = 0.5;  // depth mode: keep keypoints this much behind the person
  bool silhouettes = true;      // depth mode: drop kept keypoints whose 5 x 5 neighbourhood shows the person
  // Depth mode: the quantile of the box's central depths taken as the person's depth (estimate_person_depth).
  // The people stage uses 0.1 with a depth camera's dense depth and 0.3 with stereo's sparse keypoint depths.
  double person_depth_quantile = 0.3;
  // Depth mode with a dense depth image (RGB-D): a keypoint within the margin behind the person but
  // more than `segment_from_m` behind them is kept when it is not near the person's surface grown from
  // their box (person_segment.h): a wall or plant close behind a person, not the person's own back.
  // 0 = off.
  double segment_from_m = 0;
  void check() const;
};

struct FilterResult {
  std::vector<bool> keep;  // one flag per keypoint
  std::vector<int> box;    // per keypoint: the index (into `boxes`) of the box that removed it, -1 = kept
  int removed = 0;
  std::vector<double> person_depth_m;  // depth mode: per box (<= 0: unknown, whole box filtered)
};

// depth_m: per-keypoint depth in metres (<= 0 = none); ignored in paper mode (may be empty).
// depth_image_raw + depth_factor: used in depth mode to estimate each person's depth.
FilterResult filter_keypoints(const std::vector<cv::KeyPoint>& keypoints, const std::vector<PersonBox>& boxes,
                              const KeypointFilterOptions& options, const std::vector<float>& depth_m = {},
                              const cv::Mat& depth_image_raw = cv::Mat(), double depth_factor = 5000.0);

// Robust depth of the person in `box`: the `quantile` of the valid depths in its central region (half its
// width, 70 % of its height), low because people stand in front of what their box also contains. A
// detector's box is often wider than the person or off their centre (the body detector at 160 x 160): the
// person then covers less of the region than the background beside them, and a median there is the
// background's depth, so the filter would take the background too. Returns <= 0 when there is no depth there.
double estimate_person_depth(const cv::Mat& depth_image_raw, double depth_factor, const cv::Rect2f& box,
                             double quantile = 0.3);

}  // namespace crowdslam::people
