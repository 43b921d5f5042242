#include "crowdslam/loop/keyframe_database.h"

#include <algorithm>
#include <cassert>
#include <unordered_set>

namespace crowdslam::loop {

void KeyframeDatabase::add(const std::shared_ptr<map::KeyFrame>& keyframe) {
  assert(keyframe && keyframe->features && keyframe->features->has_bow());
  const bow::BowVector& bow = keyframe->features->bow;
  std::lock_guard lock(mutex_);
  auto [it, inserted] = keyframes_.try_emplace(keyframe->id);
  if (!inserted) return;
  it->second.keyframe = keyframe;
  it->second.words.reserve(bow.size());
  for (const auto& [word, weight] : bow) {
    it->second.words.push_back(word);
    inverted_file_[word].push_back(keyframe->id);
  }
}

void KeyframeDatabase::erase(uint64_t keyframe_id) {
  std::lock_guard lock(mutex_);
  erase_locked(keyframe_id);
}

void KeyframeDatabase::erase_locked(uint64_t keyframe_id) const {
  const auto it = keyframes_.find(keyframe_id);
  if (it == keyframes_.end()) return;
  for (const bow::WordId word : it->second.words) {
    const auto list = inverted_file_.find(word);
    if (list == inverted_file_.end()) continue;
    auto& ids = list->second;
    ids.erase(std::remove(ids.begin(), ids.end(), keyframe_id), ids.end());
    if (ids.empty()) inverted_file_.erase(list);
  }
  keyframes_.erase(it);
}

void KeyframeDatabase::clear() {
  std::lock_guard lock(mutex_);
  inverted_file_.clear();
  keyframes_.clear();
}

size_t KeyframeDatabase::size() const {
  std::lock_guard lock(mutex_);
  return keyframes_.size();
}

std::unordered_map<uint64_t, KeyframeDatabase::Shared> KeyframeDatabase::keyframes_sharing_words(
    const bow::BowVector& bow, const std::vector<uint64_t>& excluded) const {
  std::unordered_map<uint64_t, Shared> shared;
  std::unordered_set<uint64_t> skipped(excluded.begin(), excluded.end());
  std::vector<uint64_t> dropped;
  std::lock_guard lock(mutex_);
  for (const auto& [word, weight] : bow) {
    const auto list = inverted_file_.find(word);
    if (list == inverted_file_.end()) continue;
    for (const uint64_t id : list->second) {
      if (const auto s = shared.find(id); s != shared.end()) {
        ++s->second.common_words;
        continue;
      }
      if (skipped.count(id)) continue;
      const auto entry = keyframes_.find(id);
      assert(entry != keyframes_.end());
      auto keyframe = entry->second.keyframe.lock();
      if (!keyframe || keyframe->is_bad()) {
        skipped.insert(id);
        dropped.push_back(id);
        continue;
      }
      shared.emplace(id, Shared{std::move(keyframe), 1});
    }
  }
  for (const uint64_t id : dropped) erase_locked(id);
  return shared;
}

std::vector<std::shared_ptr<map::KeyFrame>> KeyframeDatabase::best_of_groups(
    const bow::BowVector& bow, std::unordered_map<uint64_t, Shared> shared, double min_score) const {
  if (shared.empty()) return {};
  int max_common = 0;
  for (const auto& [id, s] : shared) max_common = std::max(max_common, s.common_words);
  const double min_common = kMinCommonWordsRatio * max_common;

  // Scores of the keyframes sharing enough words.
  std::unordered_map<uint64_t, double> scores;
  for (const auto& [id, s] : shared) {
    if (s.common_words >= min_common) scores.emplace(id, bow::l1_score(bow, s.keyframe->features->bow));
  }

  // One group per keyframe scoring at least min_score: itself and its best covisible scored keyframes.
  struct Group {
    double accumulated = 0;
    double best_score = 0;
    std::shared_ptr<map::KeyFrame> best;
  };
  std::vector<Group> groups;
  double best_accumulated = 0;
  for (const auto& [id, score] : scores) {
    if (score < min_score) continue;
    Group group{score, score, shared.at(id).keyframe};
    for (const auto& neighbour : group.best->best_covisible(kGroupNeighbours)) {
      const auto it = scores.find(neighbour->id);
      if (it == scores.end()) continue;
      group.accumulated += it->second;
      if (it->second > group.best_score) {
        group.best_score = it->second;
        group.best = shared.at(neighbour->id).keyframe;
      }
    }
    best_accumulated = std::max(best_accumulated, group.accumulated);
    groups.push_back(std::move(group));
  }
  std::sort(groups.begin(), groups.end(), [](const Group& a, const Group& b) {
    if (a.accumulated != b.accumulated) return a.accumulated > b.accumulated;
    return a.best->id < b.best->id;
  });

  const double min_accumulated = kMinGroupScoreRatio * best_accumulated;
  std::vector<std::shared_ptr<map::KeyFrame>> candidates;
  std::unordered_set<uint64_t> returned;
  for (const auto& group : groups) {
    if (group.accumulated < min_accumulated) break;
    if (returned.insert(group.best->id).second) candidates.push_back(group.best);
  }
  return candidates;
}

std::vector<std::shared_ptr<map::KeyFrame>> KeyframeDatabase::relocalization_candidates(
    const map::FrameFeatures& frame) const {
  if (!frame.has_bow()) return {};
  return best_of_groups(frame.bow, keyframes_sharing_words(frame.bow, {}), 0.0);
}

std::vector<std::shared_ptr<map::KeyFrame>> KeyframeDatabase::loop_candidates(const map::KeyFrame& keyframe,
                                                                            double min_score) const {
  const bow::BowVector& bow = keyframe.features->bow;
  if (bow.empty()) return {};
  std::vector<uint64_t> excluded{keyframe.id};
  for (const auto& connected : keyframe.connected_keyframes()) excluded.push_back(connected->id);
  return best_of_groups(bow, keyframes_sharing_words(bow, excluded), min_score);
}

}  // namespace crowdslam::loop
