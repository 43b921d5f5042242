#pragma once
// A 3D landmark. Shared (std::shared_ptr) between the map, keyframes and the current frame; its links back
// to keyframes are weak, so culling a keyframe frees it. Thread-safe: see docs/ARCHITECTURE.md "Locking".
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "crowdslam/geometry/se3.h"
#include "crowdslam/map/scale_levels.h"

namespace crowdslam::map {

class KeyFrame;

using Descriptor = std::array<uint8_t, 32>;

class MapPoint {
 public:
  struct Observation {
    std::weak_ptr<KeyFrame> keyframe;
    size_t index = 0;  // keypoint index in that keyframe
  };
  // (keyframe id, observation) sorted by keyframe id: a flat array, not a tree. A point has a few to a
  // few dozen observations, and tracking and local mapping walk them for every local point; a
  // std::map's node hopping was 5 % of the CPU of a bonn_crowd run.
  using Observations = std::vector<std::pair<uint64_t, Observation>>;

  MapPoint(uint64_t id, const geometry::Vec3& world, const std::shared_ptr<KeyFrame>& reference_keyframe,
           uint64_t first_frame_id);

  const uint64_t id;
  const uint64_t first_keyframe_id;
  const uint64_t first_frame_id;

  // Position and viewing geometry.
  [[nodiscard]] geometry::Vec3 world() const;
  void set_world(const geometry::Vec3& world);
  [[nodiscard]] geometry::Vec3 normal() const;  // mean viewing direction (unit)
  [[nodiscard]] float min_distance() const;     // scale-invariance range (0.8 * min, 1.2 * max as ORB-SLAM)
  [[nodiscard]] float max_distance() const;
  // Pyramid level at which the point is expected to be seen from `distance` metres away.
  [[nodiscard]] int predict_scale(float distance, const ScaleLevels& levels) const;
  // All of the above under one lock (projecting ~10^4 local points per frame took five locks each).
  struct ViewGeometry {
    geometry::Vec3 world;
    geometry::Vec3 normal;
    float min_distance = 0;  // as min_distance() / max_distance()
    float max_distance = 0;
    float scale_distance = 0;  // what predict_scale uses
    [[nodiscard]] int predict_scale(float distance, const ScaleLevels& levels) const;
  };
  [[nodiscard]] ViewGeometry view_geometry() const;

  // Observations (keyframe id -> keypoint index).
  void add_observation(const std::shared_ptr<KeyFrame>& keyframe, size_t index);
  // When two or fewer observations remain the point is set bad (and so unlinked from its keyframes).
  void erase_observation(uint64_t keyframe_id);
  [[nodiscard]] Observations observations() const;
  // Calls visit(keyframe_id, observation) for each observation under the point's lock, without copying
  // them (the hot loops of tracking and local mapping). `visit` must not call back into this point; it
  // may read the observing keyframe's immutable data and its atomic flags, nothing that takes a lock.
  template <class Visit>
  void for_each_observation(Visit&& visit) const {
    std::lock_guard lock(features_mutex_);
    for (const auto& [keyframe_id, observation] : observations_) visit(keyframe_id, observation);
  }
  [[nodiscard]] int num_observations() const;  // a stereo/RGB-D observation counts twice (ORB-SLAM)
  [[nodiscard]] bool is_observed_by(uint64_t keyframe_id) const;
  [[nodiscard]] long index_in(uint64_t keyframe_id) const;  // -1 if not observed
  [[nodiscard]] std::shared_ptr<KeyFrame> reference_keyframe() const;

  // Descriptor: the observation descriptor with the least median distance to the others.
  [[nodiscard]] Descriptor descriptor() const;
  void compute_distinctive_descriptor();
  void set_descriptor(const uint8_t* descriptor);  // for points without observations (visual odometry)
  // Mean normal and scale-invariance distances from the current observations.
  void update_normal_and_depth();

  // Tracking statistics: how often the point was predicted visible / actually matched.
  void increase_visible(int n = 1);
  void increase_found(int n = 1);
  [[nodiscard]] float found_ratio() const;
  [[nodiscard]] int visible_count() const;
  [[nodiscard]] int found_count() const;
  // Geometric dynamic check (tracking/dynamic_check.h): the evidence that the point moves, as the verdicts
  // of its last kMotionWindow checked observations. record_motion adds one verdict and returns the new
  // score, the number of those verdicts that said "moving". A window, not a running sum: a static point
  // whose matches are now and then off (a wrong match, a depth edge) collects a moving verdict every few
  // observations, and a sum that only decays by one per static verdict reached any small threshold
  // sooner or later (on bonn_crowd it made static points dynamic and doubled the keyframes).
  static constexpr int kMotionWindow = 8;
  int record_motion(bool moving);
  [[nodiscard]] int motion_score() const;
  // How many of the newest verdicts in a row said "moving" (0-8).
  [[nodiscard]] int moving_run() const;

  // A pass's scratch mark (ORB-SLAM's mnTrackReferenceForFrame): a pass over many points takes a fresh
  // value from next_mark() and asks mark(value) of each point instead of keeping a hash set of the
  // points it has seen (tracking's local map: ~10^4 points per frame). Values are process-wide unique,
  // so passes of different systems or threads never mistake each other's marks; two passes over the
  // same point at the same time would, so only the tracking thread of the map's system marks.
  [[nodiscard]] static uint64_t next_mark();
  // True when the point did not carry `value` yet (and now does).
  bool mark(uint64_t value) { return pass_mark_.exchange(value, std::memory_order_relaxed) != value; }
  [[nodiscard]] bool marked(uint64_t value) const {
    return pass_mark_.load(std::memory_order_relaxed) == value;
  }

  // Saved maps (mapdb/): the viewing geometry and statistics as stored, and their restoration on load.
  struct SavedState {
    geometry::Vec3 normal = geometry::Vec3::Zero();
    float min_distance = 0;  // as kept internally (min_distance() returns 0.8 x this)
    float max_distance = 0;  // (max_distance() returns 1.2 x this)
    int visible = 1;
    int found = 1;
  };
  [[nodiscard]] SavedState saved_state() const;
  void restore(const SavedState& state, const Descriptor& descriptor);

  // Lifetime. set_bad() erases the point from every keyframe that observes it (the map removes it
  // separately, see Map::erase_map_point). replace() moves all observations to `other`.
  [[nodiscard]] bool is_bad() const;
  void set_bad();
  void replace(const std::shared_ptr<MapPoint>& other);
  [[nodiscard]] std::shared_ptr<MapPoint> replaced_by() const;

 private:
  mutable std::mutex position_mutex_;  // world_, normal_, min/max distance
  geometry::Vec3 world_;
  geometry::Vec3 normal_ = geometry::Vec3::Zero();
  float min_distance_ = 0;
  float max_distance_ = 0;

  mutable std::mutex features_mutex_;  // everything below
  Observations observations_;          // sorted by keyframe id
  // The entry of `keyframe_id`, or end(); caller holds features_mutex_.
  Observations::iterator find_observation(uint64_t keyframe_id);
  Observations::const_iterator find_observation(uint64_t keyframe_id) const;
  int num_observations_ = 0;
  std::weak_ptr<KeyFrame> reference_keyframe_;
  Descriptor descriptor_{};
  // The observations changed since descriptor_ was last computed from them (or it was set from outside):
  // compute_distinctive_descriptor() has work to do. Local mapping asks for it after each step that may
  // have added an observation, most often with nothing changed.
  bool descriptor_stale_ = true;
  // Read on every tracked frame for every local point: atomics, not the mutex (bad_ is written under
  // the mutex, with the observations it goes with).
  std::atomic<int> visible_{1};
  std::atomic<int> found_{1};
  uint8_t motion_bits_ = 0;  // the last kMotionWindow verdicts, newest in bit 0 (1 = moving)
  std::atomic<bool> bad_{false};
  std::weak_ptr<MapPoint> replaced_by_;
  std::atomic<uint64_t> pass_mark_{0};
};

}  // namespace crowdslam::map
