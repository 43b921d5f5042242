#pragma once
// The map database: owns keyframes and map points (std::shared_ptr); everything else links to them.
//
// Locking (the one place it is described; see also docs/ARCHITECTURE.md):
// - Map::mutex_ guards the keyframe and map point sets and the id counters (short critical sections).
// - update_mutex() is the "map update" lock: taken by local BA / loop correction while they write
//   optimised poses and positions back, and by tracking while it reads poses for one frame, so tracking
//   never sees a half-applied optimisation.
// - Per-object mutexes in KeyFrame (pose / features / connections) and MapPoint (position / features).
//   Lock order: update_mutex -> Map::mutex_ -> object mutexes; an object never calls another object while
//   holding its own mutex.
#include <cstdint>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <utility>
#include <vector>

namespace crowdslam::map {

class KeyFrame;
class MapPoint;

class Map {
 public:
  void add_keyframe(const std::shared_ptr<KeyFrame>& keyframe);
  void add_map_point(const std::shared_ptr<MapPoint>& point);
  void erase_keyframe(uint64_t id);
  void erase_map_point(uint64_t id);

  // Drops map points that were set bad (MapPoint::set_bad unlinks them from keyframes but cannot reach the
  // map); the local mapper calls this after culling. Returns how many were dropped.
  size_t erase_bad_map_points();

  [[nodiscard]] std::vector<std::shared_ptr<KeyFrame>> keyframes() const;    // sorted by id
  [[nodiscard]] std::vector<std::shared_ptr<MapPoint>> map_points() const;   // sorted by id
  [[nodiscard]] size_t num_keyframes() const;
  [[nodiscard]] size_t num_map_points() const;
  [[nodiscard]] std::shared_ptr<KeyFrame> keyframe(uint64_t id) const;

  uint64_t next_keyframe_id();
  uint64_t next_map_point_id();
  // Saved maps: the id counters (the next ids to hand out), and setting them on load.
  [[nodiscard]] std::pair<uint64_t, uint64_t> id_counters() const;
  void restore_id_counters(uint64_t next_keyframe_id, uint64_t next_map_point_id);

  // Incremented on every big change (loop closure, global BA) so tracking can notice.
  void notify_big_change();
  [[nodiscard]] int big_change_index() const;

  std::mutex& update_mutex() { return update_mutex_; }

  // Breaks all links (keyframe <-> point cycles through shared_ptrs) and empties the map.
  void clear();

 private:
  mutable std::mutex mutex_;
  std::unordered_map<uint64_t, std::shared_ptr<KeyFrame>> keyframes_;
  std::unordered_map<uint64_t, std::shared_ptr<MapPoint>> map_points_;
  uint64_t next_keyframe_id_ = 0;
  uint64_t next_map_point_id_ = 0;
  int big_change_index_ = 0;
  std::mutex update_mutex_;
};

}  // namespace crowdslam::map
