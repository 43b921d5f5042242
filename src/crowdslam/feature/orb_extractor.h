#pragma once
// ORB feature extractor in the manner of ORB-SLAM: scale pyramid, FAST in a grid of cells with a
// lower threshold where a cell is empty, quadtree distribution per level, intensity-centroid orientation
// and 256-bit steered BRIEF with the standard ORB pattern (descriptors compatible with cv::ORB and
// ORB vocabularies).
//
// Keypoints come back in original-image pixel coordinates (not undistorted: that is the camera's job),
// ordered by level, with octave = level, size = 31 * scale, angle in degrees [0, 360) and the FAST score as
// response. Descriptor row i (CV_8UC1, 32 bytes) belongs to keypoint i.
//
// Where this differs from ORB-SLAM2's extractor (all documented choices, not accidents):
//  - the budget is shared among levels by area (ratio 1 / scale_factor^2 per level; ORB-SLAM2 uses
//    1 / scale_factor);
//  - FAST at ini_th_fast runs once over a level's whole detection area and the 30-pixel grid only decides
//    where to retry at min_th_fast (ORB-SLAM2 calls FAST per cell): same cells and thresholds, non-max
//    suppression also across cell borders, and one cv::FAST call per level instead of one per cell
//    (about 800 per 640x480 frame, each with a fixed cost of microseconds);
//  - when the quadtree's last split overshoots a level's target, that split's weakest children are
//    dropped, so a level never returns more than its share and the total never exceeds the budget.
//
// Extraction runs in two steps. prepare() does what does not depend on the feature budget: the pyramid,
// every level's FAST corners and its Gaussian-blurred copy for the descriptors (two thirds of the work).
// extract() from a PreparedImage distributes the corners to the budget, orients them and computes their
// descriptors. The run's reader thread prepares the next frames while tracking works on this one
// (System::prepare); extract(gray, ...) does both steps here. Either way the result is the same.
//
// One extractor per thread: extract() and prepare() reuse scratch buffers between frames, so they are
// not reentrant, but separate extractors share nothing.
#include <opencv2/core.hpp>
#include <vector>

#include "crowdslam/feature/quadtree.h"

namespace crowdslam::feature {

// What ORBExtractor::prepare() computed for one image (valid with an extractor of the same options).
struct PreparedImage {
  cv::Mat gray;                                    // the image (level 0 shares its data)
  std::vector<cv::Mat> pyramid;                    // per level; levels too small to exist are empty
  std::vector<cv::Mat> blurred;                    // per level, GaussianBlur 7x7, sigma 2 (for BRIEF)
  std::vector<std::vector<cv::KeyPoint>> corners;  // per level, FAST corners in level coordinates
};

class ORBExtractor {
 public:
  struct Options {
    int num_features = 1000;    // default per-frame budget (ORBextractor.nFeatures)
    float scale_factor = 1.2f;  // scale between pyramid levels (ORBextractor.scaleFactor)
    int num_levels = 8;         // pyramid levels (ORBextractor.nLevels)
    int ini_th_fast = 20;       // FAST threshold (ORBextractor.iniThFAST)
    int min_th_fast = 7;  // FAST threshold in cells where ini_th_fast finds nothing (ORBextractor.minThFAST)
    // Throws InputError naming the first bad option and its value.
    void check() const;
  };

  ORBExtractor();
  explicit ORBExtractor(const Options& options);

  // Extracts about `num_features` keypoints (the per-frame budget; 0 gives none) from `gray`
  // (CV_8UC1). Throws InputError for an empty or non-8-bit-gray image. Images smaller than the
  // descriptor patch give no keypoints.
  void extract(const cv::Mat& gray, int num_features, std::vector<cv::KeyPoint>& keypoints,
               cv::Mat& descriptors);
  // Same with options().num_features.
  void extract(const cv::Mat& gray, std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) {
    extract(gray, options_.num_features, keypoints, descriptors);
  }
  // The budget-independent step for `gray` (same errors as extract()), into `out` (its buffers reused).
  void prepare(const cv::Mat& gray, PreparedImage& out);
  // The rest, from what an extractor with the same options prepared (throws InputError if the number
  // of levels differs). `prepared` is not changed; pyramid() then shares its levels.
  void extract(const PreparedImage& prepared, int num_features, std::vector<cv::KeyPoint>& keypoints,
               cv::Mat& descriptors);

  const Options& options() const { return options_; }
  int num_levels() const { return options_.num_levels; }
  float scale_factor() const { return options_.scale_factor; }
  // Per level l: scale_factor^l, its inverse, sigma^2 = scale^2 (keypoint position variance in level-0
  // pixels^2, relative to level 0) and its inverse.
  const std::vector<float>& scale_factors() const { return scale_factors_; }
  const std::vector<float>& inv_scale_factors() const { return inv_scale_factors_; }
  const std::vector<float>& level_sigma2() const { return level_sigma2_; }
  const std::vector<float>& inv_level_sigma2() const { return inv_level_sigma2_; }

  // How a budget of `num_features` is shared among levels: proportional to level area (ratio
  // 1 / scale_factor^2 per level), the last level taking the remainder so the sum is num_features.
  std::vector<int> features_per_level(int num_features) const;

  // Unblurred pyramid of the last extract() (level 0 shares the caller's image data); valid until the
  // next call. Levels too small to exist are empty.
  const std::vector<cv::Mat>& pyramid() const { return pyramid_; }

 private:
  void share_budget(int num_features, std::vector<int>& counts) const;
  void build_pyramid(const cv::Mat& gray, std::vector<cv::Mat>& pyramid) const;
  // Keypoints of one level in level coordinates, distributed from `corners` and oriented.
  void distribute_level(const PreparedImage& prepared, int level, int target,
                        std::vector<cv::KeyPoint>& keypoints);
  // FAST corners of `area` (level coordinates) at ini_th_fast, and at min_th_fast in grid cells where
  // ini_th_fast found none. Replaces the contents of `out`.
  void detect_fast_grid(const cv::Mat& image, const cv::Rect& area, std::vector<cv::KeyPoint>& out);

  Options options_;
  std::vector<float> scale_factors_;
  std::vector<float> inv_scale_factors_;
  std::vector<float> level_sigma2_;
  std::vector<float> inv_level_sigma2_;

  std::vector<cv::Mat> pyramid_;
  PreparedImage prepared_;  // extract(gray, ...)'s own
  std::vector<int> level_targets_;
  std::vector<std::vector<cv::KeyPoint>> level_keypoints_;
  std::vector<cv::KeyPoint> candidates_;
  std::vector<cv::KeyPoint> cell_keypoints_;
  std::vector<unsigned char> cell_has_corner_;
  QuadtreeDistributor distributor_;
};

enum class ColorOrder { kBgr, kRgb };

// 8-bit gray version of a CV_8UC1/3/4 image (CV_8UC1 is returned as is, sharing data); 3 and 4 channel
// images are read as BGR(A) or RGB(A). Throws InputError for empty images or other types.
cv::Mat to_gray(const cv::Mat& image, ColorOrder order = ColorOrder::kBgr);

}  // namespace crowdslam::feature
