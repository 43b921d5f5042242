#include "crowdslam/feature/orb_descriptor.h"

#include <cassert>
#include <cmath>

#include "crowdslam/feature/orb_pattern.h"

namespace crowdslam::feature {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Rows up to R/sqrt(2) take the rounded circle; the steeper rows are read off the flat ones by
// symmetry, so that (u, v) is inside exactly when (v, u) is.
std::array<int, kOrbHalfPatch + 1> make_half_widths() {
  constexpr int kRadius = kOrbHalfPatch;
  std::array<int, kRadius + 1> widths{};
  const int split = static_cast<int>(std::floor(kRadius / std::sqrt(2.0)));
  for (int v = 0; v <= split; ++v) {
    widths[v] = static_cast<int>(std::lround(std::sqrt(double(kRadius * kRadius - v * v))));
  }
  for (int v = split + 1; v <= kRadius; ++v) {
    int width = 0;
    for (int u = 0; u <= split; ++u) {
      if (widths[u] >= v) width = u;
    }
    widths[v] = width;
  }
  return widths;
}

constexpr int kPatternPoints = 2 * kOrbPatternSize;

// The pattern's points as floats, x and y in separate arrays (vectorisable).
struct PatternPoints {
  std::array<float, kPatternPoints> x;
  std::array<float, kPatternPoints> y;
};

const PatternPoints& pattern_points() {
  static const PatternPoints points = [] {
    PatternPoints p{};
    for (int k = 0; k < kPatternPoints; ++k) {
      p.x[k] = orb_pattern()[2 * k];
      p.y[k] = orb_pattern()[2 * k + 1];
    }
    return p;
  }();
  return points;
}

// cvRound for |v| < 2^22 under the default rounding mode (nearest, ties to even): adding and removing
// 1.5 * 2^23 leaves v rounded to an integer. Written this way so that loops of it vectorise.
// Needs IEEE arithmetic: under -ffast-math the compiler may fold the two additions away.
inline int round_half_even(float v) {
#if defined(__FAST_MATH__)
  return static_cast<int>(std::lrint(v));
#else
  constexpr float kMagic = 12582912.f;  // 1.5 * 2^23
  return static_cast<int>((v + kMagic) - kMagic);
#endif
}

bool patch_inside(const cv::Mat& image, int x, int y, int radius) {
  return x >= radius && y >= radius && x + radius < image.cols && y + radius < image.rows;
}

}  // namespace

const std::array<int, kOrbHalfPatch + 1>& circle_half_widths() {
  static const std::array<int, kOrbHalfPatch + 1> widths = make_half_widths();
  return widths;
}

float intensity_centroid_angle(const cv::Mat& image, cv::Point2f pt) {
  assert(image.type() == CV_8UC1);
  const int cx = cvRound(pt.x);
  const int cy = cvRound(pt.y);
  assert(patch_inside(image, cx, cy, kOrbHalfPatch));
  (void)patch_inside;
  const auto& widths = circle_half_widths();
  const std::uint8_t* center = image.ptr<std::uint8_t>(cy) + cx;
  const auto step = static_cast<std::ptrdiff_t>(image.step1());

  int m10 = 0;
  for (int u = -kOrbHalfPatch; u <= kOrbHalfPatch; ++u) m10 += u * center[u];
  int m01 = 0;
  for (int v = 1; v <= kOrbHalfPatch; ++v) {
    const std::uint8_t* below = center + v * step;
    const std::uint8_t* above = center - v * step;
    int row_difference = 0;
    for (int u = -widths[v]; u <= widths[v]; ++u) {
      row_difference += below[u] - above[u];
      m10 += u * (below[u] + above[u]);
    }
    m01 += v * row_difference;
  }
  return cv::fastAtan2(static_cast<float>(m01), static_cast<float>(m10));
}

void steered_brief(const cv::Mat& blurred, cv::Point2f pt, float angle_deg, std::uint8_t* descriptor) {
  assert(blurred.type() == CV_8UC1);
  const int cx = cvRound(pt.x);
  const int cy = cvRound(pt.y);
  assert(patch_inside(blurred, cx, cy, kOrbEdgeThreshold - 1));
  const std::uint8_t* center = blurred.ptr<std::uint8_t>(cy) + cx;
  const int step = static_cast<int>(blurred.step1());

  // Same float arithmetic and rounding as cv::ORB, so the bits agree exactly.
  const float angle_rad = angle_deg * static_cast<float>(kPi / 180.0);
  const float c = std::cos(angle_rad);
  const float s = std::sin(angle_rad);
  const PatternPoints& points = pattern_points();
  // Offsets of all 512 rotated points first: a branch-free loop the compiler vectorises.
  std::array<int, kPatternPoints> offsets;
  for (int k = 0; k < kPatternPoints; ++k) {
    const float x = points.x[k] * c - points.y[k] * s;
    const float y = points.x[k] * s + points.y[k] * c;
    offsets[k] = round_half_even(y) * step + round_half_even(x);
  }
  for (int byte = 0; byte < kOrbPatternSize / 8; ++byte) {
    int value = 0;
    const int* pair = &offsets[16 * byte];
    for (int bit = 0; bit < 8; ++bit) {
      value |= static_cast<int>(center[pair[2 * bit]] < center[pair[2 * bit + 1]]) << bit;
    }
    descriptor[byte] = static_cast<std::uint8_t>(value);
  }
}

}  // namespace crowdslam::feature
