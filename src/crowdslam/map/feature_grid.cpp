#include "crowdslam/map/feature_grid.h"

#include <algorithm>
#include <cmath>

namespace crowdslam::map {

FeatureGrid::FeatureGrid(const std::vector<cv::KeyPoint>& keys_un, const ImageBounds& bounds)
    : bounds_(bounds),
      min_x_(static_cast<float>(bounds.min_x)),
      min_y_(static_cast<float>(bounds.min_y)),
      inv_cell_width_(static_cast<float>(kCols / std::max(1e-3, bounds.width()))),
      inv_cell_height_(static_cast<float>(kRows / std::max(1e-3, bounds.height()))),
      cells_(static_cast<size_t>(kCols * kRows)) {
  for (size_t i = 0; i < keys_un.size(); ++i) {
    int col = 0;
    int row = 0;
    if (cell_of(keys_un[i].pt, col, row)) cells_[row * kCols + col].push_back(i);
  }
}

bool FeatureGrid::cell_of(const cv::Point2f& p, int& col, int& row) const {
  col = static_cast<int>(std::floor((p.x - min_x_) * inv_cell_width_));
  row = static_cast<int>(std::floor((p.y - min_y_) * inv_cell_height_));
  return col >= 0 && col < kCols && row >= 0 && row < kRows;
}

std::vector<size_t> FeatureGrid::features_in_area(const std::vector<cv::KeyPoint>& keys_un, float x, float y,
                                                  float radius, int min_level, int max_level) const {
  std::vector<size_t> result;
  if (cells_.empty()) return result;
  const int min_col = std::max(0, static_cast<int>(std::floor((x - min_x_ - radius) * inv_cell_width_)));
  const int max_col =
      std::min(kCols - 1, static_cast<int>(std::ceil((x - min_x_ + radius) * inv_cell_width_)));
  const int min_row = std::max(0, static_cast<int>(std::floor((y - min_y_ - radius) * inv_cell_height_)));
  const int max_row =
      std::min(kRows - 1, static_cast<int>(std::ceil((y - min_y_ + radius) * inv_cell_height_)));
  if (min_col > max_col || min_row > max_row) return result;
  const bool check_levels = min_level > 0 || max_level >= 0;
  for (int row = min_row; row <= max_row; ++row) {
    for (int col = min_col; col <= max_col; ++col) {
      for (size_t index : cells_[row * kCols + col]) {
        const cv::KeyPoint& kp = keys_un[index];
        if (check_levels) {
          if (kp.octave < min_level) continue;
          if (max_level >= 0 && kp.octave > max_level) continue;
        }
        if (std::abs(kp.pt.x - x) < radius && std::abs(kp.pt.y - y) < radius) result.push_back(index);
      }
    }
  }
  return result;
}

}  // namespace crowdslam::map
