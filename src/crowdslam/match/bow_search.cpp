#include "crowdslam/match/bow_search.h"

#include <unordered_map>
#include <utility>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/match/orb_matcher.h"
#include "crowdslam/match/rotation_histogram.h"

namespace crowdslam::match {

namespace {

bool good(const std::shared_ptr<map::MapPoint>& p) { return p && !p->is_bad(); }

// Pairs (index in a, index in b) of usable features in the same direct-index node: for each feature of
// a, the closest of b (<= kThLow, ratio test); each feature of b keeps the closest feature of a that chose
// it. Then the rotation check. `usable_b` empty = every feature of b.
std::vector<std::pair<size_t, size_t>> match_shared_nodes(const map::FrameFeatures& a, const std::vector<bool>& usable_a,
                                                          const map::FrameFeatures& b, const std::vector<bool>& usable_b,
                                                          double nn_ratio, bool check_orientation) {
  std::unordered_map<size_t, std::pair<size_t, int>> best_for_b;  // b index -> (a index, distance)
  auto ia = a.bow_features.begin();
  auto ib = b.bow_features.begin();
  while (ia != a.bow_features.end() && ib != b.bow_features.end()) {
    if (ia->first < ib->first) {
      ia = a.bow_features.lower_bound(ib->first);
      continue;
    }
    if (ib->first < ia->first) {
      ib = b.bow_features.lower_bound(ia->first);
      continue;
    }
    for (const unsigned i : ia->second) {
      if (!usable_a[i]) continue;
      BestMatch best;
      for (const unsigned j : ib->second) {
        if (!usable_b.empty() && !usable_b[j]) continue;
        const int d = feature::hamming_distance(a.descriptor(i), b.descriptor(j));
        if (d < best.distance) {
          best.second_distance = best.distance;
          best.distance = d;
          best.index = static_cast<int>(j);
        } else if (d < best.second_distance) {
          best.second_distance = d;
        }
      }
      if (best.index < 0 || best.distance > kThLow) continue;
      if (static_cast<double>(best.distance) >= nn_ratio * best.second_distance) continue;
      auto [it, inserted] = best_for_b.try_emplace(static_cast<size_t>(best.index), i, best.distance);
      if (!inserted && best.distance < it->second.second) it->second = {i, best.distance};
    }
    ++ia;
    ++ib;
  }

  std::vector<std::pair<size_t, size_t>> pairs;
  pairs.reserve(best_for_b.size());
  for (const auto& [j, match] : best_for_b) pairs.emplace_back(match.first, j);
  if (check_orientation) {
    RotationHistogram histogram;
    for (size_t k = 0; k < pairs.size(); ++k) {
      histogram.add(a.keys_un[pairs[k].first].angle - b.keys_un[pairs[k].second].angle, k);
    }
    std::vector<bool> rejected(pairs.size(), false);
    for (const size_t k : histogram.rejected()) rejected[k] = true;
    size_t kept = 0;
    for (size_t k = 0; k < pairs.size(); ++k) {
      if (!rejected[k]) pairs[kept++] = pairs[k];
    }
    pairs.resize(kept);
  }
  return pairs;
}

}  // namespace

int search_by_bow(const map::KeyFrame& keyframe, const map::Frame& frame,
                  std::vector<std::shared_ptr<map::MapPoint>>& matches, double nn_ratio, bool check_orientation) {
  matches.assign(frame.size(), nullptr);
  const map::FrameFeatures& kf = *keyframe.features;
  const map::FrameFeatures& ff = *frame.features;
  if (kf.bow_features.empty() || ff.bow_features.empty()) return 0;
  const auto points = keyframe.map_points();
  std::vector<bool> usable(points.size());
  for (size_t i = 0; i < points.size(); ++i) usable[i] = good(points[i]);
  const auto pairs = match_shared_nodes(kf, usable, ff, {}, nn_ratio, check_orientation);
  for (const auto& [i, j] : pairs) matches[j] = points[i];
  return static_cast<int>(pairs.size());
}

int search_by_bow(const map::KeyFrame& kf1, const map::KeyFrame& kf2,
                  std::vector<std::shared_ptr<map::MapPoint>>& matches_12, double nn_ratio, bool check_orientation) {
  const auto points1 = kf1.map_points();
  const auto points2 = kf2.map_points();
  matches_12.assign(points1.size(), nullptr);
  if (kf1.features->bow_features.empty() || kf2.features->bow_features.empty()) return 0;
  std::vector<bool> usable1(points1.size());
  for (size_t i = 0; i < points1.size(); ++i) usable1[i] = good(points1[i]);
  std::vector<bool> usable2(points2.size());
  bool any2 = false;
  for (size_t j = 0; j < points2.size(); ++j) {
    usable2[j] = good(points2[j]);
    any2 = any2 || usable2[j];
  }
  if (!any2) return 0;
  const auto pairs = match_shared_nodes(*kf1.features, usable1, *kf2.features, usable2, nn_ratio, check_orientation);
  for (const auto& [i, j] : pairs) matches_12[i] = points2[j];
  return static_cast<int>(pairs.size());
}

}  // namespace crowdslam::match
