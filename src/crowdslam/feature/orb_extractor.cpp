#include "crowdslam/feature/orb_extractor.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/feature/orb_descriptor.h"
#include "crowdslam/util/error.h"

namespace crowdslam::feature {
namespace {

constexpr int kCellSize = 30;   // FAST grid cell side in level pixels
constexpr int kFastRadius = 3;  // FAST ignores this many pixels at each side of its input
constexpr int kFastMinSide = 2 * kFastRadius + 1;
constexpr int kMaxLevels = 32;

[[noreturn]] void bad_option(const std::string& name, const std::string& rule, const std::string& value) {
  throw InputError("ORB extractor option " + name + " " + rule + ", got " + value);
}

}  // namespace

void ORBExtractor::Options::check() const {
  if (num_features < 0) bad_option("num_features", "must be >= 0", std::to_string(num_features));
  if (!(scale_factor > 1.f) || !std::isfinite(scale_factor)) {
    bad_option("scale_factor", "must be > 1", std::to_string(scale_factor));
  }
  if (num_levels < 1 || num_levels > kMaxLevels) {
    bad_option("num_levels", "must be in [1, " + std::to_string(kMaxLevels) + "]",
               std::to_string(num_levels));
  }
  if (ini_th_fast < 1 || ini_th_fast > 254) {
    bad_option("ini_th_fast", "must be in [1, 254]", std::to_string(ini_th_fast));
  }
  if (min_th_fast < 1 || min_th_fast > ini_th_fast) {
    bad_option("min_th_fast", "must be in [1, ini_th_fast]", std::to_string(min_th_fast));
  }
}

ORBExtractor::ORBExtractor() : ORBExtractor(Options()) {}

ORBExtractor::ORBExtractor(const Options& options) : options_(options) {
  options_.check();
  const auto levels = static_cast<std::size_t>(options_.num_levels);
  scale_factors_.resize(levels);
  inv_scale_factors_.resize(levels);
  level_sigma2_.resize(levels);
  inv_level_sigma2_.resize(levels);
  float scale = 1.f;
  for (std::size_t level = 0; level < levels; ++level) {
    scale_factors_[level] = scale;
    inv_scale_factors_[level] = 1.f / scale;
    level_sigma2_[level] = scale * scale;
    inv_level_sigma2_[level] = 1.f / (scale * scale);
    scale *= options_.scale_factor;
  }
  pyramid_.resize(levels);
  level_keypoints_.resize(levels);
}

std::vector<int> ORBExtractor::features_per_level(int num_features) const {
  std::vector<int> counts;
  share_budget(num_features, counts);
  return counts;
}

void ORBExtractor::share_budget(int num_features, std::vector<int>& counts) const {
  const int levels = options_.num_levels;
  counts.assign(static_cast<std::size_t>(levels), 0);
  if (num_features <= 0) return;
  const double area_ratio = 1.0 / (double(options_.scale_factor) * options_.scale_factor);
  double wanted = num_features * (1.0 - area_ratio) / (1.0 - std::pow(area_ratio, levels));
  int assigned = 0;
  for (int level = 0; level + 1 < levels; ++level) {
    counts[level] = std::min(static_cast<int>(std::lround(wanted)), num_features - assigned);
    assigned += counts[level];
    wanted *= area_ratio;
  }
  counts[levels - 1] = num_features - assigned;
}

void ORBExtractor::build_pyramid(const cv::Mat& gray, std::vector<cv::Mat>& pyramid) const {
  pyramid.resize(static_cast<std::size_t>(options_.num_levels));
  pyramid[0] = gray;
  for (int level = 1; level < options_.num_levels; ++level) {
    const float inv_scale = inv_scale_factors_[level];
    const cv::Size size(cvRound(gray.cols * inv_scale), cvRound(gray.rows * inv_scale));
    if (size.width < 1 || size.height < 1 || pyramid[level - 1].empty()) {
      pyramid[level].release();
      continue;
    }
    cv::resize(pyramid[level - 1], pyramid[level], size, 0, 0, cv::INTER_LINEAR);
  }
}

void ORBExtractor::detect_fast_grid(const cv::Mat& image, const cv::Rect& area,
                                    std::vector<cv::KeyPoint>& out) {
  const int num_cols = std::max(1, area.width / kCellSize);
  const int num_rows = std::max(1, area.height / kCellSize);
  const int cell_width = (area.width + num_cols - 1) / num_cols;
  const int cell_height = (area.height + num_rows - 1) / num_rows;

  // Pass 1, the whole area at ini_th_fast in one call (cv::FAST costs microseconds per call, so one
  // call per cell would dominate). Cell (row, col) owns the corners in [x0 + 3, x0 + cell_width + 3)
  // x [y0 + 3, y0 + cell_height + 3), x0 = area.x + col * cell_width: FAST skips a 3-pixel ring.
  cv::FAST(image(area), out, options_.ini_th_fast, true);
  cell_has_corner_.assign(static_cast<std::size_t>(num_rows) * static_cast<std::size_t>(num_cols), 0);
  for (cv::KeyPoint& keypoint : out) {
    const int col = std::min(num_cols - 1, (cvRound(keypoint.pt.x) - kFastRadius) / cell_width);
    const int row = std::min(num_rows - 1, (cvRound(keypoint.pt.y) - kFastRadius) / cell_height);
    cell_has_corner_[row * num_cols + col] = 1;
    keypoint.pt.x += static_cast<float>(area.x);
    keypoint.pt.y += static_cast<float>(area.y);
  }

  // Pass 2, cells without a corner again at min_th_fast, on a view of the cells plus FAST's ring. A run
  // of empty cells in a grid row is one view (fewer calls; same pixels and thresholds).
  for (int row = 0; row < num_rows; ++row) {
    const int y0 = area.y + row * cell_height;
    const int y1 = std::min(y0 + cell_height + 2 * kFastRadius, area.y + area.height);
    if (y1 - y0 < kFastMinSide) continue;
    const unsigned char* has_corner = &cell_has_corner_[static_cast<std::size_t>(row * num_cols)];
    for (int first = 0; first < num_cols;) {
      if (has_corner[first] != 0) {
        ++first;
        continue;
      }
      int last = first;
      while (last + 1 < num_cols && has_corner[last + 1] == 0) ++last;
      const int x0 = area.x + first * cell_width;
      const int x1 = std::min(area.x + (last + 1) * cell_width + 2 * kFastRadius, area.x + area.width);
      first = last + 1;
      if (x1 - x0 < kFastMinSide) continue;
      cv::FAST(image(cv::Rect(x0, y0, x1 - x0, y1 - y0)), cell_keypoints_, options_.min_th_fast, true);
      for (cv::KeyPoint& keypoint : cell_keypoints_) {
        keypoint.pt.x += static_cast<float>(x0);
        keypoint.pt.y += static_cast<float>(y0);
        out.push_back(keypoint);
      }
    }
  }
}

namespace {
void check_gray(const cv::Mat& gray) {
  if (gray.empty()) throw InputError("ORB extractor: empty image");
  if (gray.type() != CV_8UC1) {
    throw InputError("ORB extractor: image must be 8-bit gray (CV_8UC1), got type " +
                     std::to_string(gray.type()) + " with " + std::to_string(gray.channels()) + " channels");
  }
}

// FAST runs on [border, size - border) and finds corners 3 pixels further in, so every keypoint is
// kOrbEdgeThreshold pixels inside the level: the orientation and descriptor patches fit.
cv::Rect detection_area(const cv::Mat& image) {
  const int border = kOrbEdgeThreshold - kFastRadius;
  return {border, border, image.cols - 2 * border, image.rows - 2 * border};
}
}  // namespace

void ORBExtractor::prepare(const cv::Mat& gray, PreparedImage& out) {
  check_gray(gray);
  const auto levels = static_cast<std::size_t>(options_.num_levels);
  out.gray = gray;
  build_pyramid(gray, out.pyramid);
  out.blurred.resize(levels);
  out.corners.resize(levels);
  for (std::size_t level = 0; level < levels; ++level) {
    const cv::Mat& image = out.pyramid[level];
    out.corners[level].clear();
    if (image.empty()) {
      out.blurred[level].release();
      continue;
    }
    const cv::Rect area = detection_area(image);
    if (area.width >= kFastMinSide && area.height >= kFastMinSide) {
      detect_fast_grid(image, area, out.corners[level]);
    }
    // BORDER_ISOLATED keeps OpenCV on its bit-exact fixed-point path even when `gray` is a view.
    cv::GaussianBlur(image, out.blurred[level], cv::Size(7, 7), 2, 2,
                     cv::BORDER_REFLECT_101 | cv::BORDER_ISOLATED);
  }
}

void ORBExtractor::distribute_level(const PreparedImage& prepared, int level, int target,
                                    std::vector<cv::KeyPoint>& keypoints) {
  keypoints.clear();
  const cv::Mat& image = prepared.pyramid[level];
  if (image.empty() || target <= 0) return;
  const cv::Rect area = detection_area(image);
  if (area.width < kFastMinSide || area.height < kFastMinSide) return;

  candidates_ = prepared.corners[level];  // the distributor reorders its input
  distributor_.distribute(candidates_, cv::Rect2f(area), target, keypoints);

  const float size = static_cast<float>(kOrbPatchSize) * scale_factors_[level];
  for (cv::KeyPoint& keypoint : keypoints) {
    keypoint.angle = intensity_centroid_angle(image, keypoint.pt);
    keypoint.octave = level;
    keypoint.size = size;
  }
}

void ORBExtractor::extract(const cv::Mat& gray, int num_features, std::vector<cv::KeyPoint>& keypoints,
                           cv::Mat& descriptors) {
  prepare(gray, prepared_);
  extract(prepared_, num_features, keypoints, descriptors);
}

void ORBExtractor::extract(const PreparedImage& prepared, int num_features,
                           std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) {
  check_gray(prepared.gray);
  if (prepared.pyramid.size() != static_cast<std::size_t>(options_.num_levels) ||
      prepared.blurred.size() != prepared.pyramid.size() ||
      prepared.corners.size() != prepared.pyramid.size()) {
    throw InputError("ORB extractor: the prepared image has " + std::to_string(prepared.pyramid.size()) +
                     " levels, the extractor " + std::to_string(options_.num_levels));
  }
  assert(num_features >= 0);
  pyramid_ = prepared.pyramid;

  share_budget(std::max(num_features, 0), level_targets_);
  std::size_t total = 0;
  for (int level = 0; level < options_.num_levels; ++level) {
    distribute_level(prepared, level, level_targets_[level], level_keypoints_[level]);
    total += level_keypoints_[level].size();
  }

  keypoints.clear();
  keypoints.reserve(total);
  descriptors.create(static_cast<int>(total), kDescriptorBytes, CV_8UC1);
  const cv::Mat& gray = prepared.gray;
  int row = 0;
  for (int level = 0; level < options_.num_levels; ++level) {
    std::vector<cv::KeyPoint>& level_keypoints = level_keypoints_[level];
    if (level_keypoints.empty()) continue;
    const cv::Mat& image = pyramid_[level];
    const cv::Mat& blurred = prepared.blurred[level];
    // Level -> level-0 pixel coordinates with pixel centres at integers. cv::resize (INTER_LINEAR)
    // aligns pixel centres, so the exact map is x0 = (x + 0.5) * (w0 / w) - 0.5; ORB-SLAM's x0 = x * s
    // puts level-l keypoints up to 0.5 (s_l - 1) px (1.3 px at level 7) up and to the left.
    const float scale_x = static_cast<float>(gray.cols) / static_cast<float>(image.cols);
    const float scale_y = static_cast<float>(gray.rows) / static_cast<float>(image.rows);
    for (cv::KeyPoint keypoint : level_keypoints) {
      steered_brief(blurred, keypoint.pt, keypoint.angle, descriptors.ptr<std::uint8_t>(row++));
      keypoint.pt.x = (keypoint.pt.x + 0.5f) * scale_x - 0.5f;
      keypoint.pt.y = (keypoint.pt.y + 0.5f) * scale_y - 0.5f;
      keypoints.push_back(keypoint);
    }
  }
}

cv::Mat to_gray(const cv::Mat& image, ColorOrder order) {
  if (image.empty()) throw InputError("to_gray: empty image");
  const bool rgb = order == ColorOrder::kRgb;
  cv::Mat gray;
  switch (image.type()) {
    case CV_8UC1:
      return image;
    case CV_8UC3:
      cv::cvtColor(image, gray, rgb ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY);
      return gray;
    case CV_8UC4:
      cv::cvtColor(image, gray, rgb ? cv::COLOR_RGBA2GRAY : cv::COLOR_BGRA2GRAY);
      return gray;
    default:
      throw InputError("to_gray: unsupported image type " + std::to_string(image.type()) +
                       " (need 8-bit, 1, 3 or 4 channels)");
  }
}

}  // namespace crowdslam::feature
