#pragma once
// A keyframe: a frame kept in the map, with its features (immutable, shared with the frame it came from),
// its pose, its map point associations, and its place in the covisibility graph and spanning tree.
// Thread-safe: see docs/ARCHITECTURE.md "Locking" (pose, features and connections have separate mutexes;
// no method calls into another object while holding its own lock).
#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <vector>

#include "crowdslam/geometry/camera.h"
#include "crowdslam/geometry/se3.h"
#include "crowdslam/map/frame_features.h"
#include "crowdslam/map/scale_levels.h"

namespace crowdslam::map {

class MapPoint;
class Map;

class KeyFrame : public std::enable_shared_from_this<KeyFrame> {
 public:
  KeyFrame(uint64_t id, uint64_t frame_id, double timestamp_s,
           std::shared_ptr<const geometry::PinholeCamera> camera, std::shared_ptr<const ScaleLevels> levels,
           std::shared_ptr<const FrameFeatures> features, const geometry::SE3& cam_from_world);

  const uint64_t id;
  const uint64_t frame_id;
  const double timestamp_s;
  const std::shared_ptr<const geometry::PinholeCamera> camera;
  const std::shared_ptr<const ScaleLevels> levels;
  const std::shared_ptr<const FrameFeatures> features;

  // The pose tracking measured for this keyframe relative to an earlier keyframe (RGB-D and stereo: the
  // keyframe before it, when every frame in between was tracked): local bundle adjustment keeps the two
  // near it (LocalMapperOptions::odometry_sigma_deg). Set by tracking before the keyframe is handed to
  // the mapper, read-only afterwards; not saved with a map.
  struct Odometry {
    uint64_t other_id = 0;
    geometry::SE3 cam_from_other;
    double median_depth = 0;  // of the keyframe's map points, for the translation's sigma
  };
  std::optional<Odometry> odometry;

  // Pose.
  [[nodiscard]] geometry::SE3 cam_from_world() const;
  [[nodiscard]] geometry::SE3 world_from_cam() const;
  [[nodiscard]] geometry::Vec3 camera_center() const;
  void set_cam_from_world(const geometry::SE3& cam_from_world);

  // Map point associations, one slot per keypoint.
  void add_map_point(size_t index, const std::shared_ptr<MapPoint>& point);
  void erase_map_point(size_t index);
  void replace_map_point(size_t index, const std::shared_ptr<MapPoint>& point);
  [[nodiscard]] std::shared_ptr<MapPoint> map_point(size_t index) const;
  [[nodiscard]] std::vector<std::shared_ptr<MapPoint>> map_points() const;        // copy, with nulls
  [[nodiscard]] std::vector<std::shared_ptr<MapPoint>> valid_map_points() const;  // non-null, not bad
  // Calls visit(point) for each non-null slot under the keyframe's lock, without copying the list (the
  // local map of tracking: ~10^4 points per frame). `visit` must take no lock (a point's atomics, such as
  // is_bad() and mark(), are fine) and must not call back into this keyframe.
  template <class Visit>
  void for_each_map_point(Visit&& visit) const {
    std::lock_guard lock(features_mutex_);
    for (const auto& point : map_points_) {
      if (point) visit(point);
    }
  }
  // Number of good points with at least `min_observations` observations.
  [[nodiscard]] int tracked_map_points(int min_observations) const;
  // Number of good points that tracking has matched in at least `min_found` frames (MapPoint::found_count).
  [[nodiscard]] int found_map_points(int min_found) const;

  // Covisibility graph: weight = number of shared map points.
  void update_connections();  // recompute from the map points (edge threshold 15, else the best one)
  void add_connection(const std::shared_ptr<KeyFrame>& other, int weight);
  void erase_connection(uint64_t other_id);
  [[nodiscard]] std::vector<std::shared_ptr<KeyFrame>> connected_keyframes() const;  // all, by weight desc
  [[nodiscard]] std::vector<std::shared_ptr<KeyFrame>> best_covisible(size_t n) const;
  [[nodiscard]] std::vector<std::shared_ptr<KeyFrame>> covisible_by_weight(int min_weight) const;
  [[nodiscard]] int weight(uint64_t other_id) const;

  // Spanning tree and loop edges.
  [[nodiscard]] std::shared_ptr<KeyFrame> parent() const;
  [[nodiscard]] std::vector<std::shared_ptr<KeyFrame>> children() const;
  void add_child(const std::shared_ptr<KeyFrame>& child);
  void erase_child(uint64_t child_id);
  void change_parent(const std::shared_ptr<KeyFrame>& parent);
  void add_loop_edge(const std::shared_ptr<KeyFrame>& other);
  // Saved maps: sets the spanning-tree parent as stored (null for a root) and marks the keyframe as
  // already attached, so a later update_connections() keeps the stored tree.
  void restore_parent(const std::shared_ptr<KeyFrame>& parent);
  [[nodiscard]] std::vector<std::shared_ptr<KeyFrame>> loop_edges() const;

  // Lifetime. set_bad() unlinks the keyframe from its points and neighbours, repairs the spanning tree
  // (children are re-attached to the covisible candidate with the highest weight) and removes it from
  // `map`. Keyframe 0 is never erased; while protected (set_not_erase, loop closing) the erase is deferred
  // until set_erase().
  void set_bad(Map& map);
  [[nodiscard]] bool is_bad() const;
  void set_not_erase();
  void set_erase(Map& map);
  // Drops every strong link (points, parent, connections); used when the whole map is discarded.
  void release_links();
  // Pose of this keyframe relative to its parent at the time it was erased (for trajectory output).
  [[nodiscard]] geometry::SE3 cam_from_parent_at_erase() const;

  // Median depth of the map points seen (q = 2: median), for scaling and keyframe policy.
  [[nodiscard]] float scene_median_depth() const;
  [[nodiscard]] bool is_in_image(double u, double v) const {
    return features->grid.bounds().contains({u, v});
  }

 private:
  void update_best_covisibles_locked();

  mutable std::mutex pose_mutex_;
  geometry::SE3 cam_from_world_;
  geometry::SE3 world_from_cam_;

  mutable std::mutex features_mutex_;
  std::vector<std::shared_ptr<MapPoint>> map_points_;

  mutable std::mutex connections_mutex_;
  std::map<uint64_t, std::pair<std::weak_ptr<KeyFrame>, int>> connections_;
  std::vector<std::pair<int, std::weak_ptr<KeyFrame>>> ordered_connections_;  // weight desc
  bool first_connection_ = true;
  // Strong: a bad keyframe keeps its chain to the tree (trajectory output).
  std::shared_ptr<KeyFrame> parent_;
  std::map<uint64_t, std::weak_ptr<KeyFrame>> children_;
  std::map<uint64_t, std::weak_ptr<KeyFrame>> loop_edges_;
  bool not_erase_ = false;
  bool to_be_erased_ = false;
  std::atomic<bool> bad_{false};  // written under connections_mutex_; is_bad() reads it without the lock
  geometry::SE3 cam_from_parent_;
};

}  // namespace crowdslam::map
