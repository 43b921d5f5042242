#pragma once
// Helpers shared by the synth tests: reprojection consistency between two frames.
#include <opencv2/core.hpp>

#include "crowdslam/geometry/se3.h"
#include "crowdslam/synth/options.h"

namespace crowdslam::synth::test {

struct Consistency {
  int sampled = 0;         // pixels of frame i with depth (not on people)
  int inside = 0;          // ... that project inside frame j, in front of it
  int depth_agrees = 0;    // ... whose predicted depth matches frame j's depth within 1%
  double median_grey_diff = 255.0;  // over the depth-agreeing pixels (not on people in j either)
};

// Back-projects every `step`-th pixel of frame i with its depth, moves it into frame j with the poses,
// compares depth (nearest pixel) and colour (bilinear) there. Labels may be empty (no people).
Consistency check_consistency(const cv::Mat& colour_i, const cv::Mat& depth_i, const cv::Mat& label_i,
                              const geometry::SE3& world_from_i, const cv::Mat& colour_j, const cv::Mat& depth_j,
                              const cv::Mat& label_j, const geometry::SE3& world_from_j, const Intrinsics& k,
                              int step = 2);

}  // namespace crowdslam::synth::test
