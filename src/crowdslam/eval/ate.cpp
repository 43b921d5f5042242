#include "crowdslam/eval/ate.h"

#include <cmath>
#include <cstdio>

#include "crowdslam/eval/unique_stamps.h"
#include "crowdslam/util/error.h"

namespace crowdslam::eval {
namespace {

constexpr std::size_t kMinMatches = 3;

std::string format_seconds(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%g", value);
  return buffer;
}

void require_not_empty(const io::Trajectory& trajectory, const std::string& name) {
  if (trajectory.empty()) throw input_error(name, "trajectory has no poses");
}

}  // namespace

const char* to_string(Alignment alignment) {
  switch (alignment) {
    case Alignment::kSe3:
      return "se3";
    case Alignment::kSim3:
      return "sim3";
    case Alignment::kNone:
      return "none";
  }
  return "unknown";
}

Alignment parse_alignment(const std::string& text) {
  if (text == "se3") return Alignment::kSe3;
  if (text == "sim3") return Alignment::kSim3;
  if (text == "none") return Alignment::kNone;
  throw InputError("alignment must be se3, sim3 or none, got '" + text + "'");
}

void AteOptions::check() const {
  if (!(std::isfinite(max_difference_s) && max_difference_s > 0)) {
    throw InputError("max_difference_s (--max-diff) must be a positive number of seconds, got " +
                     format_seconds(max_difference_s));
  }
  if (!std::isfinite(offset_s))
    throw InputError("offset_s (--offset) must be finite, got " + format_seconds(offset_s));
  if (!(std::isfinite(scale) && scale > 0)) {
    throw InputError("scale (--scale) must be positive and finite, got " + format_seconds(scale));
  }
}

AteResult evaluate_ate(const io::Trajectory& ground_truth, const io::Trajectory& estimate,
                       const AteOptions& options, const std::string& ground_truth_name,
                       const std::string& estimate_name) {
  options.check();
  require_not_empty(ground_truth, ground_truth_name);
  require_not_empty(estimate, estimate_name);
  const io::Trajectory gt = unique_sorted_by_stamp(ground_truth);
  const io::Trajectory est = unique_sorted_by_stamp(estimate);

  AteResult result;
  result.ground_truth_poses = gt.size();
  result.estimate_poses = est.size();
  result.matches =
      io::associate_timestamps(stamps_of(gt), stamps_of(est), options.max_difference_s, options.offset_s);
  const std::size_t n = result.matches.size();
  if (n == 0) {
    throw InputError("no overlapping timestamps between ground truth " + ground_truth_name +
                     " and estimate " + estimate_name + " within " +
                     format_seconds(options.max_difference_s) + " s (offset " +
                     format_seconds(options.offset_s) + " s)");
  }
  if (n < kMinMatches) {
    throw InputError("only " + std::to_string(n) + " pose(s) of estimate " + estimate_name +
                     " match ground truth " + ground_truth_name + " within " +
                     format_seconds(options.max_difference_s) + " s; need at least 3");
  }

  Eigen::Matrix3Xd model(3, static_cast<Eigen::Index>(n));
  Eigen::Matrix3Xd data(3, static_cast<Eigen::Index>(n));
  for (std::size_t k = 0; k < n; ++k) {
    const auto col = static_cast<Eigen::Index>(k);
    model.col(col) = options.scale * est[result.matches[k].second_index].world_from_cam.translation();
    data.col(col) = gt[result.matches[k].first_index].world_from_cam.translation();
  }
  if (options.alignment != Alignment::kNone) {
    result.alignment = geometry::align_umeyama(model, data, options.alignment == Alignment::kSim3);
  }
  result.errors_m.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const auto col = static_cast<Eigen::Index>(k);
    result.errors_m.push_back((result.alignment.apply(model.col(col)) - data.col(col)).norm());
  }
  result.translation_error_m = compute_error_stats(result.errors_m);
  return result;
}

io::Trajectory apply_alignment(const io::Trajectory& estimate, const geometry::Similarity& alignment,
                               double scale) {
  io::Trajectory aligned;
  aligned.reserve(estimate.size());
  for (const io::StampedPose& pose : estimate) {
    const geometry::Vec3 position = alignment.apply(scale * pose.world_from_cam.translation());
    const geometry::Mat3 rotation = alignment.rotation * pose.world_from_cam.rotation_matrix();
    aligned.push_back({pose.timestamp_s, geometry::SE3(rotation, position)});
  }
  return aligned;
}

}  // namespace crowdslam::eval
