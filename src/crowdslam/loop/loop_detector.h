#pragma once
// Loop detection (ORB-SLAM's place recognition with temporal consistency): the keyframe database gives
// keyframes that look like the new one (not its covisible neighbours, scoring at least as well as the
// worst neighbour); a candidate is accepted only when its covisibility group is consistent with groups
// of candidates of `consistency_threshold` consecutive previous keyframes.
#include <cstdint>
#include <memory>
#include <set>
#include <vector>

#include "crowdslam/map/keyframe.h"

namespace crowdslam::loop {

class KeyframeDatabase;

class LoopDetector {
 public:
  explicit LoopDetector(int consistency_threshold = 3) : consistency_threshold_(consistency_threshold) {}

  struct Detection {
    std::vector<std::shared_ptr<map::KeyFrame>> consistent;  // candidates consistent over consecutive keyframes
    std::vector<std::shared_ptr<map::KeyFrame>> others;      // this keyframe's other candidates, best score first
  };
  // The candidates for `keyframe` (none consistent: no loop yet). Updates the consistency groups.
  Detection detect(const map::KeyFrame& keyframe, const KeyframeDatabase& database);

  // Consistency bookkeeping on its own (for tests): candidates of the current keyframe and their groups
  // (each candidate with its covisible keyframes, as ids). Returns the indices of consistent candidates.
  std::vector<size_t> update_consistency(const std::vector<std::set<uint64_t>>& candidate_groups);

  void reset() { previous_groups_.clear(); }

 private:
  struct Group {
    std::set<uint64_t> keyframe_ids;
    int consistency = 0;
  };
  int consistency_threshold_;
  std::vector<Group> previous_groups_;
};

// Lowest BoW score between the keyframe and its covisible neighbours (1 when it has none).
double min_neighbour_score(const map::KeyFrame& keyframe);

}  // namespace crowdslam::loop
