#pragma once
// Stereo matching of ORB keypoints between the two images of a rectified pair (the method of the
// ORB-SLAM2 paper, our implementation): each left keypoint gets a right-image u coordinate and a depth.
//
//  1. Row band: a right keypoint at row v and pyramid level l is a candidate for every left keypoint on
//     rows v - band_factor * scale_l .. v + band_factor * scale_l (rows are indexed once per frame).
//  2. Disparity range: u_R in [u_L - max_disparity, u_L - min_disparity], with max_disparity =
//     bf / min_depth_m and min_disparity = 0; pyramid levels within one of each other.
//  3. Descriptor: the candidate with the smallest Hamming distance, accepted below
//     max_descriptor_distance.
//  4. Sub-pixel refinement on the left keypoint's pyramid level: zero-mean SAD of a (2 h + 1)^2 window
//     around the left keypoint against the right image shifted by -sad_search_px..+sad_search_px around
//     the matched right keypoint; the minimum must be interior, and a parabola through it and its two
//     neighbours gives the sub-pixel offset (at most one pixel). The parabola is fitted to the sum of
//     squared differences (SSD) of those three shifts by default: SAD is V-shaped around its minimum, so
//     a parabola through SAD values pulls the offset towards whole pixels ("pixel locking"). Measured on
//     a texture warped by a known sub-pixel disparity (tests/tracking/test_stereo_matcher.cpp): median
//     error 0.033 px with the SSD fit, 0.070 px with the SAD fit.
//  5. Outliers: matches whose SAD exceeds max(outlier_factor * median SAD of the frame, min_outlier_sad)
//     are dropped (SAD as mean absolute difference per pixel of the zero-mean windows, in grey levels).
//
// Depth = bf / disparity (level-0 pixels). Keypoint coordinates are level-0 pixels of the rectified
// images; pyramid level l maps to level 0 as the ORB extractor does: x0 = (x + 0.5) w0 / w_l - 0.5.
#include <opencv2/core.hpp>
#include <vector>

#include "crowdslam/map/scale_levels.h"

namespace crowdslam::tracking {

struct StereoMatcherOptions {
  int max_descriptor_distance = 75;  // (kThHigh + kThLow) / 2 of the ORB matcher
  double band_factor = 2.0;          // candidate rows: +- band_factor * scale of the right keypoint's level
  double min_depth_m = 0.0;          // nearest depth searched; 0 = one baseline (max disparity = fx)
  int sad_half_window = 5;           // 11 x 11 window
  int sad_search_px = 5;             // +- pixels at the keypoint's level
  bool parabola_on_ssd = true;       // sub-pixel parabola through SSD (true) or SAD (false) costs
  double outlier_factor = 1.5 * 1.4; // SAD above this times the median SAD is an outlier ...
  double min_outlier_sad = 1.0;      // ... but never below this (grey levels per pixel): near-perfect
                                     // images (synthetic) would otherwise drop every imperfect match
  void check() const;                // throws InputError naming the bad option
};

// One image of the pair: keypoints (level-0 pixels, octave = level), descriptors (row i = keys[i]) and
// the unblurred pyramid the keypoints were detected on (level 0 = the image).
struct StereoView {
  const std::vector<cv::KeyPoint>& keys;
  const cv::Mat& descriptors;
  const std::vector<cv::Mat>& pyramid;
};

struct StereoMatches {
  std::vector<float> right_u;  // per left keypoint: right-image u (level-0 pixels); -1 = no match
  std::vector<float> depth_m;  // per left keypoint: bf / disparity; -1 = no match
  std::vector<float> sad;      // per left keypoint: mean absolute zero-mean difference; -1 = no match
  int descriptor_matches = 0;  // accepted by the descriptor test
  int refined = 0;             // of those, kept by the SAD refinement
  int outliers = 0;            // of those, rejected by the SAD statistics
  int matched = 0;             // final
};

class StereoMatcher {
 public:
  // bf = baseline * fx (pixels * metres), fx in pixels; both > 0.
  StereoMatcher(const StereoMatcherOptions& options, const map::ScaleLevels& levels, double bf, double fx);

  // Matches every left keypoint. Both views must have the same image size and pyramid depth.
  void match(const StereoView& left, const StereoView& right, StereoMatches& out);

  [[nodiscard]] double max_disparity() const { return max_disparity_; }
  [[nodiscard]] const StereoMatcherOptions& options() const { return options_; }

 private:
  // Sub-pixel right coordinate at level-0 for a left keypoint matched to u_right (level 0); false when the
  // window leaves the image, the minimum is at the search border, or the parabola is degenerate.
  bool refine(const cv::Mat& left_level, const cv::Mat& right_level, cv::Size full, float u_left, float v_left,
              float u_right, float& refined_u_right, float& cost) const;

  StereoMatcherOptions options_;
  map::ScaleLevels levels_;
  double bf_;
  double max_disparity_;
  std::vector<std::vector<int>> rows_;  // per image row: right keypoints whose band covers it
};

}  // namespace crowdslam::tracking
