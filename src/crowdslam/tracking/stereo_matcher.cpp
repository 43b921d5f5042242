#include "crowdslam/tracking/stereo_matcher.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/match/orb_matcher.h"
#include "crowdslam/util/error.h"

namespace crowdslam::tracking {

static_assert(StereoMatcherOptions{}.max_descriptor_distance == (match::kThHigh + match::kThLow) / 2,
              "default stereo descriptor threshold is the mean of the ORB matcher's two thresholds");

namespace {
// Level coordinate of a level-0 coordinate (inverse of the extractor's x0 = (x + 0.5) * s - 0.5).
inline float to_level(float x0, float level_over_full) { return (x0 + 0.5f) * level_over_full - 0.5f; }
inline float to_full(float x, float full_over_level) { return (x + 0.5f) * full_over_level - 0.5f; }

constexpr int kMaxWindow = 31;  // sad_half_window limit, so the window fits the stack buffer
}  // namespace

void StereoMatcherOptions::check() const {
  auto fail = [](const std::string& key, double value) {
    throw InputError("stereo matcher: " + key + " out of range: " + std::to_string(value));
  };
  if (max_descriptor_distance < 0 || max_descriptor_distance > 256) fail("max_descriptor_distance", max_descriptor_distance);
  if (!(band_factor > 0)) fail("band_factor", band_factor);
  if (!(min_depth_m >= 0)) fail("min_depth_m", min_depth_m);
  if (sad_half_window < 1 || sad_half_window > kMaxWindow / 2) fail("sad_half_window", sad_half_window);
  if (sad_search_px < 1 || sad_search_px > 64) fail("sad_search_px", sad_search_px);
  if (!(outlier_factor > 0)) fail("outlier_factor", outlier_factor);
  if (!(min_outlier_sad >= 0)) fail("min_outlier_sad", min_outlier_sad);
}

StereoMatcher::StereoMatcher(const StereoMatcherOptions& options, const map::ScaleLevels& levels, double bf,
                             double fx)
    : options_(options), levels_(levels), bf_(bf) {
  options_.check();
  if (!(bf > 0) || !(fx > 0)) throw InputError("stereo matching needs Camera.bf > 0 and Camera.fx > 0");
  const double min_depth = options_.min_depth_m > 0 ? options_.min_depth_m : bf / fx;
  max_disparity_ = bf / min_depth;
}

bool StereoMatcher::refine(const cv::Mat& left_level, const cv::Mat& right_level, cv::Size full, float u_left,
                           float v_left, float u_right, float& refined_u_right, float& cost) const {
  const float level_over_full_x = static_cast<float>(left_level.cols) / static_cast<float>(full.width);
  const float level_over_full_y = static_cast<float>(left_level.rows) / static_cast<float>(full.height);
  const int xl = cvRound(to_level(u_left, level_over_full_x));
  const int yl = cvRound(to_level(v_left, level_over_full_y));
  const int xr = cvRound(to_level(u_right, level_over_full_x));
  const int h = options_.sad_half_window;
  const int search = options_.sad_search_px;
  if (yl - h < 0 || yl + h >= left_level.rows || xl - h < 0 || xl + h >= left_level.cols) return false;
  if (xr - search - h < 0 || xr + search + h >= right_level.cols) return false;

  // Zero-mean windows without division: compare n * value - sum (n = pixels in the window).
  const int side = 2 * h + 1;
  const int n = side * side;
  int left_window[kMaxWindow * kMaxWindow];
  int left_sum = 0;
  for (int dy = -h; dy <= h; ++dy) {
    const uint8_t* row = left_level.ptr<uint8_t>(yl + dy);
    for (int dx = -h; dx <= h; ++dx) left_sum += row[xl + dx];
  }
  for (int dy = -h, k = 0; dy <= h; ++dy) {
    const uint8_t* row = left_level.ptr<uint8_t>(yl + dy);
    for (int dx = -h; dx <= h; ++dx) left_window[k++] = n * row[xl + dx] - left_sum;
  }
  // Column sums of the right strip give each shifted window's sum.
  const int strip_first = xr - search - h;
  const int strip_width = 2 * (search + h) + 1;
  int column_sum[2 * (64 + kMaxWindow / 2) + 1];
  std::fill(column_sum, column_sum + strip_width, 0);
  for (int dy = -h; dy <= h; ++dy) {
    const uint8_t* row = right_level.ptr<uint8_t>(yl + dy) + strip_first;
    for (int x = 0; x < strip_width; ++x) column_sum[x] += row[x];
  }
  const int shifts = 2 * search + 1;
  int sad_costs[2 * 64 + 1];
  double ssd_costs[2 * 64 + 1];
  int best = 0;
  for (int s = 0; s < shifts; ++s) {
    int right_sum = 0;
    for (int x = s; x < s + side; ++x) right_sum += column_sum[x];
    int sad = 0;
    int64_t ssd = 0;
    for (int dy = -h, k = 0; dy <= h; ++dy) {
      const uint8_t* row = right_level.ptr<uint8_t>(yl + dy) + strip_first + s;
      for (int x = 0; x < side; ++x) {
        const int d = left_window[k++] - (n * row[x] - right_sum);
        sad += std::abs(d);
        ssd += static_cast<int64_t>(d) * d;
      }
    }
    sad_costs[s] = sad;
    ssd_costs[s] = static_cast<double>(ssd);
    if (sad < sad_costs[best]) best = s;
  }
  // A minimum at the border of the search may lie outside it.
  if (best == 0 || best == shifts - 1) return false;
  const bool ssd = options_.parabola_on_ssd;
  const double c_minus = ssd ? ssd_costs[best - 1] : sad_costs[best - 1];
  const double c_zero = ssd ? ssd_costs[best] : sad_costs[best];
  const double c_plus = ssd ? ssd_costs[best + 1] : sad_costs[best + 1];
  const double curvature = 2.0 * (c_minus + c_plus - 2.0 * c_zero);
  const double delta = curvature > 0 ? (c_minus - c_plus) / curvature : 0.0;
  if (std::abs(delta) > 1.0) return false;
  const double x_refined = xr + (best - search) + delta;
  refined_u_right = to_full(static_cast<float>(x_refined), static_cast<float>(full.width) / left_level.cols);
  cost = static_cast<float>(sad_costs[best] / (static_cast<double>(n) * n));
  return true;
}

void StereoMatcher::match(const StereoView& left, const StereoView& right, StereoMatches& out) {
  const size_t n_left = left.keys.size();
  out = StereoMatches{};
  out.right_u.assign(n_left, -1.0f);
  out.depth_m.assign(n_left, -1.0f);
  out.sad.assign(n_left, -1.0f);
  if (n_left == 0 || right.keys.empty() || left.pyramid.empty() || right.pyramid.empty()) return;
  const cv::Mat& left0 = left.pyramid[0];
  assert(left0.size() == right.pyramid[0].size());
  assert(left.pyramid.size() == right.pyramid.size());
  assert(left.descriptors.rows == static_cast<int>(n_left));
  assert(right.descriptors.rows == static_cast<int>(right.keys.size()));

  // Row index of the right keypoints.
  const int rows = left0.rows;
  rows_.resize(static_cast<size_t>(rows));
  for (auto& r : rows_) r.clear();
  for (size_t j = 0; j < right.keys.size(); ++j) {
    const cv::KeyPoint& k = right.keys[j];
    const int level = std::clamp(k.octave, 0, levels_.num_levels - 1);
    const float band = static_cast<float>(options_.band_factor) * levels_.scale[level];
    const int first = std::max(0, static_cast<int>(std::floor(k.pt.y - band)));
    const int last = std::min(rows - 1, static_cast<int>(std::ceil(k.pt.y + band)));
    for (int y = first; y <= last; ++y) rows_[static_cast<size_t>(y)].push_back(static_cast<int>(j));
  }

  const float max_disparity = static_cast<float>(max_disparity_);
  const int num_pyramid = static_cast<int>(left.pyramid.size());
  std::vector<std::pair<float, size_t>> costs;
  costs.reserve(n_left);
  for (size_t i = 0; i < n_left; ++i) {
    const cv::KeyPoint& kl = left.keys[i];
    const int row = cvRound(kl.pt.y);
    if (row < 0 || row >= rows) continue;
    const float u_left = kl.pt.x;
    const float min_u = u_left - max_disparity;
    const float max_u = u_left;  // minimum disparity 0
    const uint8_t* dl = left.descriptors.ptr<uint8_t>(static_cast<int>(i));
    int best_distance = options_.max_descriptor_distance;
    int best = -1;
    for (const int j : rows_[static_cast<size_t>(row)]) {
      const cv::KeyPoint& kr = right.keys[static_cast<size_t>(j)];
      if (kr.octave < kl.octave - 1 || kr.octave > kl.octave + 1) continue;
      if (kr.pt.x < min_u || kr.pt.x > max_u) continue;
      const int d = feature::hamming_distance(dl, right.descriptors.ptr<uint8_t>(j));
      if (d < best_distance) {
        best_distance = d;
        best = j;
      }
    }
    if (best < 0) continue;
    ++out.descriptor_matches;

    const int level = std::clamp(kl.octave, 0, num_pyramid - 1);
    const cv::Mat& left_level = left.pyramid[static_cast<size_t>(level)];
    const cv::Mat& right_level = right.pyramid[static_cast<size_t>(level)];
    if (left_level.empty() || right_level.empty()) continue;
    float u_right = 0;
    float cost = 0;
    if (!refine(left_level, right_level, left0.size(), u_left, kl.pt.y, right.keys[static_cast<size_t>(best)].pt.x, u_right,
                cost)) {
      continue;
    }
    const float disparity = u_left - u_right;
    if (!(disparity > 0) || disparity > max_disparity) continue;
    ++out.refined;
    out.right_u[i] = u_right;
    out.depth_m[i] = static_cast<float>(bf_ / disparity);
    out.sad[i] = cost;
    costs.emplace_back(cost, i);
  }
  if (costs.empty()) return;

  // Outliers by the frame's SAD statistics.
  std::vector<std::pair<float, size_t>> sorted = costs;
  const auto middle = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), middle, sorted.end());
  const float threshold =
      std::max(static_cast<float>(options_.outlier_factor) * middle->first, static_cast<float>(options_.min_outlier_sad));
  for (const auto& [cost, i] : costs) {
    if (cost > threshold) {
      out.right_u[i] = -1.0f;
      out.depth_m[i] = -1.0f;
      out.sad[i] = -1.0f;
      ++out.outliers;
    } else {
      ++out.matched;
    }
  }
}

}  // namespace crowdslam::tracking
