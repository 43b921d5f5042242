#pragma once
// Summary statistics of a list of errors, as TUM's evaluate_ate.py / evaluate_rpe.py print them.
#include <cstddef>
#include <vector>

namespace crowdslam::eval {

struct ErrorStats {
  std::size_t count = 0;
  double rmse = 0.0;  // sqrt(sum e^2 / N)
  double mean = 0.0;
  double median = 0.0;  // numpy.median: mean of the two middle values for even N
  double std = 0.0;     // population standard deviation (numpy.std, ddof = 0)
  double min = 0.0;
  double max = 0.0;
};

// `errors` must not be empty.
ErrorStats compute_error_stats(std::vector<double> errors);

// Every field multiplied by `factor` (count unchanged), e.g. radians to degrees.
ErrorStats scaled(const ErrorStats& stats, double factor);

}  // namespace crowdslam::eval
