#pragma once
// Keyframe database for place recognition (relocalisation and loop detection, as in ORB-SLAM: Mur-Artal,
// Montiel & Tardos 2015, sec. "place recognition"; our own code): an inverted file from each vocabulary
// word to the keyframes whose bag of words contains it.
//
// Keyframes are held weakly (a culled or discarded keyframe is not kept alive); bad or expired keyframes
// are skipped by the queries and dropped from the index as they are met. erase() removes one explicitly.
//
// Thread-safe: one internal mutex guards the index. Tracking queries it for relocalisation, the local
// mapper adds keyframes and the loop closer queries it, each from its own thread. The mutex is held only
// while the index is read or changed; scoring and the covisibility lookups run unlocked. Lock order:
// (Map::update_mutex ->) database mutex -> keyframe mutexes; keyframes never call the database.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "crowdslam/bow/bow_vector.h"
#include "crowdslam/map/frame_features.h"
#include "crowdslam/map/keyframe.h"

namespace crowdslam::loop {

class KeyframeDatabase {
 public:
  // Fraction of the largest number of words shared with the query that a keyframe needs to be scored.
  static constexpr double kMinCommonWordsRatio = 0.8;
  // Groups whose accumulated score reaches this fraction of the best group's are returned.
  static constexpr double kMinGroupScoreRatio = 0.75;
  // A candidate's group: itself and up to this many best covisible keyframes.
  static constexpr size_t kGroupNeighbours = 10;

  // Indexes the keyframe under every word of keyframe->features->bow (which must not be empty: assert).
  // Adding a keyframe that is already indexed does nothing.
  void add(const std::shared_ptr<map::KeyFrame>& keyframe);
  void erase(uint64_t keyframe_id);
  void clear();
  // Keyframes indexed (including ones that went bad and were not dropped yet).
  [[nodiscard]] size_t size() const;

  // Keyframes similar to a frame being relocalised (ORB-SLAM's DetectRelocalizationCandidates):
  // keyframes sharing words with it; of those, the ones sharing at least 0.8 x the most shared words are
  // scored (L1 score of the bags of words). Each scored keyframe's group score adds the scores of its 10
  // best covisible keyframes that were scored too; of every group reaching 0.75 x the best group score,
  // the group's best scoring keyframe is returned, once, ordered by group score (best first).
  // Empty if the frame has no bag of words.
  [[nodiscard]] std::vector<std::shared_ptr<map::KeyFrame>> relocalization_candidates(
      const map::FrameFeatures& frame) const;

  // Loop candidates for `keyframe` (ORB-SLAM's DetectLoopCandidates): as above, but the keyframe itself and
  // its connected (covisible) keyframes are never candidates nor group members, and only keyframes scoring
  // at least `min_score` start a group (group members count whatever their score).
  [[nodiscard]] std::vector<std::shared_ptr<map::KeyFrame>> loop_candidates(const map::KeyFrame& keyframe,
                                                                          double min_score) const;

 private:
  struct Entry {
    std::weak_ptr<map::KeyFrame> keyframe;
    std::vector<bow::WordId> words;  // to unlink the keyframe from the inverted file
  };
  struct Shared {
    std::shared_ptr<map::KeyFrame> keyframe;
    int common_words = 0;
  };

  // Keyframes sharing words with `bow`, except the `excluded` ids; drops bad or expired keyframes met.
  [[nodiscard]] std::unordered_map<uint64_t, Shared> keyframes_sharing_words(
      const bow::BowVector& bow, const std::vector<uint64_t>& excluded) const;
  [[nodiscard]] std::vector<std::shared_ptr<map::KeyFrame>> best_of_groups(const bow::BowVector& bow,
                                                                           std::unordered_map<uint64_t, Shared> shared,
                                                                           double min_score) const;
  void erase_locked(uint64_t keyframe_id) const;

  mutable std::mutex mutex_;
  // Mutable: queries drop keyframes that went bad (under the mutex).
  mutable std::unordered_map<bow::WordId, std::vector<uint64_t>> inverted_file_;
  mutable std::unordered_map<uint64_t, Entry> keyframes_;
};

}  // namespace crowdslam::loop
