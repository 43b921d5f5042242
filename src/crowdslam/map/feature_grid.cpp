#include "crowdslam/map/feature_grid.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace crowdslam::map {

FeatureGrid::FeatureGrid(const std::vector<cv::KeyPoint>& keys_un, const ImageBounds& bounds)
    : bounds_(bounds),
      min_x_(static_cast<float>(bounds.min_x)),
      min_y_(static_cast<float>(bounds.min_y)),
      inv_cell_width_(static_cast<float>(kCols / std::max(1e-3, bounds.width()))),
      inv_cell_height_(static_cast<float>(kRows / std::max(1e-3, bounds.height()))),
      cell_start_(static_cast<size_t>(kCols * kRows) + 1, 0) {
  assert(keys_un.size() < std::numeric_limits<unsigned>::max());
  // Counting sort by cell: keypoints outside the grid get cell -1 and no entry.
  std::vector<int> cell(keys_un.size(), -1);
  for (size_t i = 0; i < keys_un.size(); ++i) {
    int col = 0;
    int row = 0;
    if (!cell_of(keys_un[i].pt, col, row)) continue;
    cell[i] = row * kCols + col;
    ++cell_start_[static_cast<size_t>(cell[i]) + 1];
  }
  for (size_t c = 1; c < cell_start_.size(); ++c) cell_start_[c] += cell_start_[c - 1];
  entries_.resize(cell_start_.back());
  std::vector<unsigned> next(cell_start_.begin(), cell_start_.end() - 1);
  for (size_t i = 0; i < keys_un.size(); ++i) {
    if (cell[i] < 0) continue;
    const cv::KeyPoint& kp = keys_un[i];
    entries_[next[static_cast<size_t>(cell[i])]++] = {kp.pt.x, kp.pt.y, kp.octave, static_cast<unsigned>(i)};
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
  if (cell_start_.empty()) return result;
  (void)keys_un;  // the grid keeps their positions and octaves
  const int min_col = std::max(0, static_cast<int>(std::floor((x - min_x_ - radius) * inv_cell_width_)));
  const int max_col =
      std::min(kCols - 1, static_cast<int>(std::ceil((x - min_x_ + radius) * inv_cell_width_)));
  const int min_row = std::max(0, static_cast<int>(std::floor((y - min_y_ - radius) * inv_cell_height_)));
  const int max_row =
      std::min(kRows - 1, static_cast<int>(std::ceil((y - min_y_ + radius) * inv_cell_height_)));
  if (min_col > max_col || min_row > max_row) return result;
  const bool check_levels = min_level > 0 || max_level >= 0;
  for (int row = min_row; row <= max_row; ++row) {
    // Cells min_col..max_col of a row are one run of entries.
    const Entry* e = entries_.data() + cell_start_[static_cast<size_t>(row * kCols + min_col)];
    const Entry* end = entries_.data() + cell_start_[static_cast<size_t>(row * kCols + max_col + 1)];
    for (; e != end; ++e) {
      if (check_levels) {
        if (e->octave < min_level) continue;
        if (max_level >= 0 && e->octave > max_level) continue;
      }
      if (std::abs(e->x - x) < radius && std::abs(e->y - y) < radius) result.push_back(e->index);
    }
  }
  return result;
}

}  // namespace crowdslam::map
