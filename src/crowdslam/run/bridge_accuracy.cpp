#include "crowdslam/run/bridge_accuracy.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "crowdslam/eval/unique_stamps.h"
#include "crowdslam/io/associate.h"
#include "crowdslam/run/run_document.h"

namespace crowdslam::run {
namespace {

struct Entry {
  double stamp_s = 0;
  bool bridged = false;
  std::optional<double> error_m;  // none when the ground truth has no pose near the stamp
};

// Each pose's position error after the alignment (none without a ground-truth pose within the window).
void add_errors(const io::Trajectory& ground_truth, const io::Trajectory& poses, const eval::AteResult& ate,
                double max_difference_s, bool bridged, std::vector<Entry>& entries) {
  const io::Trajectory aligned = eval::apply_alignment(poses, ate.alignment, 1.0);
  std::vector<std::optional<double>> errors(poses.size());
  for (const auto& a : io::associate_timestamps(eval::stamps_of(ground_truth), eval::stamps_of(aligned),
                                                max_difference_s)) {
    const auto& gt = ground_truth[a.first_index].world_from_cam.translation();
    errors[a.second_index] = (aligned[a.second_index].world_from_cam.translation() - gt).norm();
  }
  for (size_t i = 0; i < poses.size(); ++i) entries.push_back({poses[i].timestamp_s, bridged, errors[i]});
}

}  // namespace

nlohmann::json bridge_accuracy(const io::Trajectory& ground_truth, const io::Trajectory& tracked,
                               const io::Trajectory& bridged, const eval::AteResult& ate,
                               double max_difference_s, size_t max_bridges) {
  if (bridged.empty()) return nullptr;
  const io::Trajectory truth = eval::unique_sorted_by_stamp(ground_truth);
  std::vector<Entry> entries;
  add_errors(truth, tracked, ate, max_difference_s, false, entries);
  add_errors(truth, bridged, ate, max_difference_s, true, entries);
  std::stable_sort(entries.begin(), entries.end(),
                   [](const Entry& a, const Entry& b) { return a.stamp_s < b.stamp_s; });

  nlohmann::json list = nlohmann::json::array();
  size_t bridges = 0;
  size_t evaluated = 0;
  double sum_sq = 0;
  double worst = 0;
  double longest_s = 0;
  std::optional<double> worst_ratio;  // error after / error before, over the bridges with both
  for (size_t i = 0; i < entries.size();) {
    if (!entries[i].bridged) {
      ++i;
      continue;
    }
    size_t end = i;
    std::optional<double> max_error;
    while (end < entries.size() && entries[end].bridged) {
      if (const auto& e = entries[end].error_m) {
        max_error = std::max(max_error.value_or(0.0), *e);
        sum_sq += *e * *e;
        ++evaluated;
      }
      ++end;
    }
    const std::optional<double> before = i > 0 ? entries[i - 1].error_m : std::nullopt;
    const std::optional<double> after = end < entries.size() ? entries[end].error_m : std::nullopt;
    // From the last tracked frame before the bridge to the first after it (or its last bridged frame).
    const double span_s = (end < entries.size() ? entries[end].stamp_s : entries[end - 1].stamp_s) -
                          (i > 0 ? entries[i - 1].stamp_s : entries[i].stamp_s);
    longest_s = std::max(longest_s, span_s);
    if (max_error) worst = std::max(worst, *max_error);
    if (before && after && *before > 0) worst_ratio = std::max(worst_ratio.value_or(0.0), *after / *before);
    if (bridges < max_bridges) {
      list.push_back({{"first_stamp", entries[i].stamp_s},
                      {"last_stamp", entries[end - 1].stamp_s},
                      {"frames", end - i},
                      {"span_s", span_s},
                      {"error_before_m", optional_json(before)},
                      {"error_max_m", optional_json(max_error)},
                      {"error_after_m", optional_json(after)}});
    }
    ++bridges;
    i = end;
  }
  return {{"frames", bridged.size()},
          {"bridges", bridges},
          {"longest_s", longest_s},
          {"error_rmse_m", evaluated > 0 ? nlohmann::json(std::sqrt(sum_sq / static_cast<double>(evaluated)))
                                         : nlohmann::json(nullptr)},
          {"error_max_m", evaluated > 0 ? nlohmann::json(worst) : nlohmann::json(nullptr)},
          {"after_over_before_max", optional_json(worst_ratio)},
          {"list", list}};
}

}  // namespace crowdslam::run
