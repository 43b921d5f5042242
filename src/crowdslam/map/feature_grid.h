#pragma once
// A fixed grid over the (undistorted) image that buckets keypoint indices, for fast "features within r
// pixels of (x, y)" queries in the matcher's searches. The buckets are one array sorted by cell (row-major,
// then keypoint index) with each entry's position and octave beside its index, so a query reads one
// contiguous run per grid row and never the keypoints themselves.
#include <opencv2/core/types.hpp>
#include <vector>

#include "crowdslam/geometry/camera.h"

namespace crowdslam::map {

using geometry::ImageBounds;

class FeatureGrid {
 public:
  static constexpr int kCols = 64;
  static constexpr int kRows = 48;

  FeatureGrid() = default;
  FeatureGrid(const std::vector<cv::KeyPoint>& keys_un, const ImageBounds& bounds);

  // Indices of keypoints within the square of half-side `radius` around (x, y) (and inside the circle's
  // bounding square, as the searches expect), optionally restricted to octaves [min_level, max_level]
  // (-1 = no limit); by cell (row-major), then by index. `keys_un` must be the keypoints the grid was
  // built from (their positions and octaves are kept in the grid).
  [[nodiscard]] std::vector<size_t> features_in_area(const std::vector<cv::KeyPoint>& keys_un, float x, float y,
                                                     float radius, int min_level = -1, int max_level = -1) const;
  [[nodiscard]] const ImageBounds& bounds() const { return bounds_; }

 private:
  bool cell_of(const cv::Point2f& p, int& col, int& row) const;
  ImageBounds bounds_;
  float min_x_ = 0;
  float min_y_ = 0;
  float inv_cell_width_ = 0;
  float inv_cell_height_ = 0;
  struct Entry {
    float x, y;
    int octave;
    unsigned index;
  };
  std::vector<Entry> entries_;        // sorted by cell, then index
  std::vector<unsigned> cell_start_;  // kRows x kCols + 1 offsets into entries_ (empty: no grid)
};

}  // namespace crowdslam::map
