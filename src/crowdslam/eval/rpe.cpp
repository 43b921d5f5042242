#include "crowdslam/eval/rpe.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "crowdslam/eval/unique_stamps.h"
#include "crowdslam/util/error.h"

namespace crowdslam::eval {
namespace {

using geometry::SE3;

constexpr double kPi = 3.14159265358979323846;

std::string format_number(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%g", value);
  return buffer;
}

// The script's ominus(a, b) = inv(a) * b and scale(a, s) (translation times s).
SE3 ominus(const SE3& a, const SE3& b) { return a.inverse() * b; }
SE3 scale_translation(const SE3& a, double s) { return SE3(a.rotation(), s * a.translation()); }

double rotation_angle_as_script(const SE3& transform) {
  const double cosine = (transform.rotation_matrix().trace() - 1.0) / 2.0;
  return std::acos(std::min(1.0, std::max(-1.0, cosine)));
}

double median_interval(const std::vector<double>& sorted) {
  std::vector<double> intervals;
  for (std::size_t k = 1; k < sorted.size(); ++k) intervals.push_back(sorted[k] - sorted[k - 1]);
  return compute_error_stats(intervals).median;
}

// Distinct estimate stamps reachable est -> closest gt -> closest est, as the script's overlap check.
std::size_t count_overlap(const std::vector<double>& gt, const std::vector<double>& est, double offset) {
  std::vector<double> returned;
  for (double t_est : est) {
    const double t_gt = gt[find_closest_index(gt, t_est + offset)];
    const double t_est_return = est[find_closest_index(est, t_gt - offset)];
    if (std::find(returned.begin(), returned.end(), t_est_return) == returned.end())
      returned.push_back(t_est_return);
  }
  return returned.size();
}

std::vector<std::pair<std::size_t, std::size_t>> fixed_delta_pairs(const std::vector<double>& est_stamps,
                                                                   const RpeOptions& options) {
  std::vector<double> index = est_stamps;
  if (options.delta_unit == DeltaUnit::kFrames) {
    for (std::size_t k = 0; k < index.size(); ++k) index[k] = static_cast<double>(k);
  }
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < index.size(); ++i) {
    const std::size_t j = find_closest_index(index, index[i] + options.delta);
    if (j != index.size() - 1) pairs.emplace_back(i, j);
  }
  return pairs;
}

}  // namespace

const char* to_string(DeltaUnit unit) { return unit == DeltaUnit::kSeconds ? "s" : "frames"; }

DeltaUnit parse_delta_unit(const std::string& text) {
  if (text == "s") return DeltaUnit::kSeconds;
  if (text == "frames" || text == "f") return DeltaUnit::kFrames;
  throw InputError("delta unit must be s or frames, got '" + text + "'");
}

void RpeOptions::check() const {
  if (!(std::isfinite(delta) && delta > 0))
    throw InputError("delta (--delta) must be positive, got " + format_number(delta));
  if (!std::isfinite(offset_s))
    throw InputError("offset_s (--offset) must be finite, got " + format_number(offset_s));
  if (!(std::isfinite(scale) && scale > 0)) {
    throw InputError("scale (--scale) must be positive and finite, got " + format_number(scale));
  }
}

std::size_t find_closest_index(const std::vector<double>& sorted, double value) {
  std::size_t beginning = 0;
  std::size_t end = sorted.size();
  double difference = std::abs(sorted[0] - value);
  std::size_t best = 0;
  while (beginning < end) {
    const std::size_t middle = (end + beginning) / 2;
    if (std::abs(sorted[middle] - value) < difference) {
      difference = std::abs(sorted[middle] - value);
      best = middle;
    }
    if (value == sorted[middle]) return middle;
    if (sorted[middle] > value) {
      end = middle;
    } else {
      beginning = middle + 1;
    }
  }
  return best;
}

RpeResult evaluate_rpe(const io::Trajectory& ground_truth, const io::Trajectory& estimate,
                       const RpeOptions& options, const std::string& ground_truth_name,
                       const std::string& estimate_name) {
  options.check();
  if (ground_truth.empty()) throw input_error(ground_truth_name, "trajectory has no poses");
  if (estimate.empty()) throw input_error(estimate_name, "trajectory has no poses");
  const io::Trajectory gt = unique_sorted_by_stamp(ground_truth);
  const io::Trajectory est = unique_sorted_by_stamp(estimate);
  const std::vector<double> gt_stamps = stamps_of(gt);
  const std::vector<double> est_stamps = stamps_of(est);

  if (count_overlap(gt_stamps, est_stamps, options.offset_s) < 2) {
    throw InputError("number of overlapping timestamps between ground truth " + ground_truth_name +
                     " and estimate " + estimate_name + " is too small (need 2)");
  }
  RpeResult result;
  result.ground_truth_max_time_difference_s = 2.0 * median_interval(gt_stamps);
  const double max_difference = result.ground_truth_max_time_difference_s;

  for (const auto& [i, j] : fixed_delta_pairs(est_stamps, options)) {
    const double est_0 = est_stamps[i] + options.offset_s;
    const double est_1 = est_stamps[j] + options.offset_s;
    const std::size_t gt_0 = find_closest_index(gt_stamps, est_0);
    const std::size_t gt_1 = find_closest_index(gt_stamps, est_1);
    if (std::abs(gt_stamps[gt_0] - est_0) > max_difference ||
        std::abs(gt_stamps[gt_1] - est_1) > max_difference) {
      continue;
    }
    const SE3 est_motion =
        scale_translation(ominus(est[j].world_from_cam, est[i].world_from_cam), options.scale);
    const SE3 gt_motion = ominus(gt[gt_1].world_from_cam, gt[gt_0].world_from_cam);
    const SE3 error = ominus(est_motion, gt_motion);
    result.pairs.push_back({est_stamps[i], est_stamps[j], gt_stamps[gt_0], gt_stamps[gt_1],
                            error.translation().norm(), rotation_angle_as_script(error)});
  }
  if (result.pairs.size() < 2) {
    throw InputError("couldn't find matching timestamp pairs between ground truth " + ground_truth_name +
                     " and estimate " + estimate_name + " (delta " + format_number(options.delta) + " " +
                     to_string(options.delta_unit) + ", " + std::to_string(result.pairs.size()) +
                     " pair(s))");
  }
  std::vector<double> translation;
  std::vector<double> rotation;
  for (const RpePair& pair : result.pairs) {
    translation.push_back(pair.translation_error_m);
    rotation.push_back(pair.rotation_error_rad);
  }
  result.translation_error_m = compute_error_stats(translation);
  result.rotation_error_deg = scaled(compute_error_stats(rotation), 180.0 / kPi);
  return result;
}

}  // namespace crowdslam::eval
