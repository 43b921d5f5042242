#include "crowdslam/loop/loop_detector.h"

#include <algorithm>

#include "crowdslam/bow/bow_vector.h"
#include "crowdslam/loop/keyframe_database.h"

namespace crowdslam::loop {

double min_neighbour_score(const map::KeyFrame& keyframe) {
  double min_score = 1.0;
  for (const auto& neighbour : keyframe.connected_keyframes()) {
    if (neighbour->is_bad()) continue;
    min_score = std::min(min_score, bow::l1_score(keyframe.features->bow, neighbour->features->bow));
  }
  return min_score;
}

std::vector<size_t> LoopDetector::update_consistency(const std::vector<std::set<uint64_t>>& candidate_groups) {
  std::vector<Group> current_groups;
  std::vector<bool> previous_used(previous_groups_.size(), false);
  std::vector<size_t> consistent;
  for (size_t c = 0; c < candidate_groups.size(); ++c) {
    const auto& group = candidate_groups[c];
    bool enough = false;
    bool consistent_with_any = false;
    for (size_t g = 0; g < previous_groups_.size(); ++g) {
      const auto& previous = previous_groups_[g].keyframe_ids;
      const bool shares = std::any_of(group.begin(), group.end(), [&](uint64_t id) { return previous.count(id) > 0; });
      if (!shares) continue;
      consistent_with_any = true;
      const int consistency = previous_groups_[g].consistency + 1;
      if (!previous_used[g]) {
        current_groups.push_back({group, consistency});
        previous_used[g] = true;
      }
      if (consistency >= consistency_threshold_ && !enough) {
        consistent.push_back(c);
        enough = true;  // a candidate is reported once
      }
    }
    if (!consistent_with_any) current_groups.push_back({group, 0});
  }
  previous_groups_ = std::move(current_groups);
  return consistent;
}

LoopDetector::Detection LoopDetector::detect(const map::KeyFrame& keyframe, const KeyframeDatabase& database) {
  const double min_score = min_neighbour_score(keyframe);
  auto candidates = database.loop_candidates(keyframe, min_score);
  if (candidates.empty()) {
    previous_groups_.clear();
    return {};
  }
  std::vector<std::set<uint64_t>> groups;
  groups.reserve(candidates.size());
  for (const auto& candidate : candidates) {
    std::set<uint64_t> group{candidate->id};
    for (const auto& kf : candidate->connected_keyframes()) group.insert(kf->id);
    groups.push_back(std::move(group));
  }
  Detection detection;
  std::vector<bool> is_consistent(candidates.size(), false);
  for (size_t index : update_consistency(groups)) {
    detection.consistent.push_back(candidates[index]);
    is_consistent[index] = true;
  }
  for (size_t c = 0; c < candidates.size(); ++c) {
    if (!is_consistent[c]) detection.others.push_back(candidates[c]);
  }
  return detection;
}

}  // namespace crowdslam::loop
