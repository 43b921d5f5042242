#include "crowdslam/people/feature_budget.h"

#include <algorithm>
#include <cmath>

#include "crowdslam/util/error.h"

namespace crowdslam::people {

void FeatureBudgetOptions::check() const {
  if (base_features <= 0) throw InputError("ORBextractor.nFeatures must be > 0");
  if (image_width <= 0 || image_height <= 0) throw InputError("feature budget: image size must be positive");
  if (factors.size() != thresholds.size() + 1) {
    throw InputError("FeatureBudget.factors must have one more entry than FeatureBudget.thresholds");
  }
  for (size_t i = 1; i < thresholds.size(); ++i) {
    if (!(thresholds[i] > thresholds[i - 1])) throw InputError("FeatureBudget.thresholds must increase");
  }
  for (double f : factors) {
    if (!(f > 0)) throw InputError("FeatureBudget.factors must be > 0");
  }
}

double covered_fraction(const std::vector<PersonBox>& boxes, int width, int height, AreaMode mode) {
  const cv::Rect2f image(0, 0, static_cast<float>(width), static_cast<float>(height));
  std::vector<cv::Rect2f> rects;
  for (const auto& b : boxes) {
    if (!(b.box.width > 0) || !(b.box.height > 0) || !std::isfinite(b.box.x) || !std::isfinite(b.box.y))
      continue;
    const cv::Rect2f r = b.box & image;
    if (r.width > 0 && r.height > 0) rects.push_back(r);
  }
  const double image_area = static_cast<double>(width) * height;
  if (rects.empty() || image_area <= 0) return 0.0;
  if (mode == AreaMode::kSum) {
    double sum = 0;
    for (const auto& r : rects) sum += static_cast<double>(r.width) * r.height;
    return sum / image_area;
  }
  // Union by coordinate compression: O(n^3) for n boxes, trivial for the few boxes of a frame.
  std::vector<double> xs, ys;
  for (const auto& r : rects) {
    xs.push_back(r.x);
    xs.push_back(r.x + r.width);
    ys.push_back(r.y);
    ys.push_back(r.y + r.height);
  }
  std::sort(xs.begin(), xs.end());
  std::sort(ys.begin(), ys.end());
  double area = 0;
  for (size_t i = 0; i + 1 < xs.size(); ++i) {
    const double x0 = xs[i], x1 = xs[i + 1];
    if (x1 <= x0) continue;
    const double xm = 0.5 * (x0 + x1);
    for (size_t j = 0; j + 1 < ys.size(); ++j) {
      const double y0 = ys[j], y1 = ys[j + 1];
      if (y1 <= y0) continue;
      const double ym = 0.5 * (y0 + y1);
      for (const auto& r : rects) {
        if (xm > r.x && xm < r.x + r.width && ym > r.y && ym < r.y + r.height) {
          area += (x1 - x0) * (y1 - y0);
          break;
        }
      }
    }
  }
  return area / image_area;
}

double budget_factor(double covered, const FeatureBudgetOptions& options) {
  if (!options.enabled || !(covered > options.thresholds.front())) return options.factors.front();
  for (size_t i = 1; i < options.thresholds.size(); ++i) {
    if (covered < options.thresholds[i]) return options.factors[i];
  }
  return options.factors.back();
}

int feature_budget(double covered, const FeatureBudgetOptions& options) {
  const double area_scale = static_cast<double>(options.image_width) * options.image_height / (640.0 * 480.0);
  return std::max(
      1, static_cast<int>(std::lround(options.base_features * area_scale * budget_factor(covered, options))));
}

}  // namespace crowdslam::people
