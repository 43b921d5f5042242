#include "crowdslam/map/map.h"

#include <algorithm>

#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map_point.h"

namespace crowdslam::map {

void Map::add_keyframe(const std::shared_ptr<KeyFrame>& keyframe) {
  std::lock_guard lock(mutex_);
  keyframes_[keyframe->id] = keyframe;
}

void Map::add_map_point(const std::shared_ptr<MapPoint>& point) {
  std::lock_guard lock(mutex_);
  map_points_[point->id] = point;
}

void Map::erase_keyframe(uint64_t id) {
  std::lock_guard lock(mutex_);
  keyframes_.erase(id);
}

void Map::erase_map_point(uint64_t id) {
  std::lock_guard lock(mutex_);
  map_points_.erase(id);
}

size_t Map::erase_bad_map_points() {
  std::lock_guard lock(mutex_);
  size_t erased = 0;
  for (auto it = map_points_.begin(); it != map_points_.end();) {
    if (it->second->is_bad()) {
      it = map_points_.erase(it);
      ++erased;
    } else {
      ++it;
    }
  }
  return erased;
}

std::vector<std::shared_ptr<KeyFrame>> Map::keyframes() const {
  std::vector<std::shared_ptr<KeyFrame>> result;
  {
    std::lock_guard lock(mutex_);
    result.reserve(keyframes_.size());
    for (const auto& [id, kf] : keyframes_) result.push_back(kf);
  }
  std::sort(result.begin(), result.end(), [](const auto& a, const auto& b) { return a->id < b->id; });
  return result;
}

std::vector<std::shared_ptr<MapPoint>> Map::map_points() const {
  std::vector<std::shared_ptr<MapPoint>> result;
  {
    std::lock_guard lock(mutex_);
    result.reserve(map_points_.size());
    for (const auto& [id, p] : map_points_) result.push_back(p);
  }
  std::sort(result.begin(), result.end(), [](const auto& a, const auto& b) { return a->id < b->id; });
  return result;
}

size_t Map::num_keyframes() const {
  std::lock_guard lock(mutex_);
  return keyframes_.size();
}

size_t Map::num_map_points() const {
  std::lock_guard lock(mutex_);
  return map_points_.size();
}

std::shared_ptr<KeyFrame> Map::keyframe(uint64_t id) const {
  std::lock_guard lock(mutex_);
  auto it = keyframes_.find(id);
  return it == keyframes_.end() ? nullptr : it->second;
}

uint64_t Map::next_keyframe_id() {
  std::lock_guard lock(mutex_);
  return next_keyframe_id_++;
}

uint64_t Map::next_map_point_id() {
  std::lock_guard lock(mutex_);
  return next_map_point_id_++;
}

void Map::notify_big_change() {
  std::lock_guard lock(mutex_);
  ++big_change_index_;
}

int Map::big_change_index() const {
  std::lock_guard lock(mutex_);
  return big_change_index_;
}

void Map::clear() {
  std::unordered_map<uint64_t, std::shared_ptr<KeyFrame>> keyframes;
  std::unordered_map<uint64_t, std::shared_ptr<MapPoint>> points;
  {
    std::lock_guard lock(mutex_);
    keyframes.swap(keyframes_);
    points.swap(map_points_);
    next_keyframe_id_ = 0;
    next_map_point_id_ = 0;
  }
  // Keyframes hold strong links to points and parents: cut them so everything is freed.
  for (auto& [id, kf] : keyframes) kf->release_links();
}

std::pair<uint64_t, uint64_t> Map::id_counters() const {
  std::lock_guard lock(mutex_);
  return {next_keyframe_id_, next_map_point_id_};
}

void Map::restore_id_counters(uint64_t next_keyframe_id, uint64_t next_map_point_id) {
  std::lock_guard lock(mutex_);
  next_keyframe_id_ = next_keyframe_id;
  next_map_point_id_ = next_map_point_id;
}

}  // namespace crowdslam::map
