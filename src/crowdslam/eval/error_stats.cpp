#include "crowdslam/eval/error_stats.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace crowdslam::eval {

ErrorStats compute_error_stats(std::vector<double> errors) {
  assert(!errors.empty());
  ErrorStats stats;
  const std::size_t n = errors.size();
  stats.count = n;
  std::sort(errors.begin(), errors.end());
  double sum = 0.0;
  double sum_squares = 0.0;
  for (double e : errors) {
    sum += e;
    sum_squares += e * e;
  }
  const double count = static_cast<double>(n);
  stats.rmse = std::sqrt(sum_squares / count);
  stats.mean = sum / count;
  stats.median = n % 2 == 1 ? errors[n / 2] : 0.5 * (errors[n / 2 - 1] + errors[n / 2]);
  double sum_deviations = 0.0;
  for (double e : errors) sum_deviations += (e - stats.mean) * (e - stats.mean);
  stats.std = std::sqrt(sum_deviations / count);
  stats.min = errors.front();
  stats.max = errors.back();
  return stats;
}

ErrorStats scaled(const ErrorStats& stats, double factor) {
  ErrorStats result = stats;
  result.rmse *= factor;
  result.mean *= factor;
  result.median *= factor;
  result.std *= factor;
  result.min *= factor;
  result.max *= factor;
  return result;
}

}  // namespace crowdslam::eval
