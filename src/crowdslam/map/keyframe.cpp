#include "crowdslam/map/keyframe.h"

#include <algorithm>
#include <limits>

#include "crowdslam/map/map.h"
#include "crowdslam/map/map_point.h"

namespace crowdslam::map {

KeyFrame::KeyFrame(uint64_t id_in, uint64_t frame_id_in, double timestamp_s_in,
                   std::shared_ptr<const geometry::PinholeCamera> camera_in,
                   std::shared_ptr<const ScaleLevels> levels_in,
                   std::shared_ptr<const FrameFeatures> features_in, const geometry::SE3& cam_from_world)
    : id(id_in),
      frame_id(frame_id_in),
      timestamp_s(timestamp_s_in),
      camera(std::move(camera_in)),
      levels(std::move(levels_in)),
      features(std::move(features_in)),
      cam_from_world_(cam_from_world),
      world_from_cam_(cam_from_world.inverse()),
      map_points_(features->size()) {}

// ---- pose ----
geometry::SE3 KeyFrame::cam_from_world() const {
  std::lock_guard lock(pose_mutex_);
  return cam_from_world_;
}

geometry::SE3 KeyFrame::world_from_cam() const {
  std::lock_guard lock(pose_mutex_);
  return world_from_cam_;
}

geometry::Vec3 KeyFrame::camera_center() const {
  std::lock_guard lock(pose_mutex_);
  return world_from_cam_.translation();
}

void KeyFrame::set_cam_from_world(const geometry::SE3& cam_from_world) {
  std::lock_guard lock(pose_mutex_);
  cam_from_world_ = cam_from_world;
  world_from_cam_ = cam_from_world.inverse();
}

// ---- map points ----
void KeyFrame::add_map_point(size_t index, const std::shared_ptr<MapPoint>& point) {
  std::lock_guard lock(features_mutex_);
  map_points_[index] = point;
}

void KeyFrame::erase_map_point(size_t index) {
  std::lock_guard lock(features_mutex_);
  map_points_[index].reset();
}

void KeyFrame::replace_map_point(size_t index, const std::shared_ptr<MapPoint>& point) {
  std::lock_guard lock(features_mutex_);
  map_points_[index] = point;
}

std::shared_ptr<MapPoint> KeyFrame::map_point(size_t index) const {
  std::lock_guard lock(features_mutex_);
  return map_points_[index];
}

std::vector<std::shared_ptr<MapPoint>> KeyFrame::map_points() const {
  std::lock_guard lock(features_mutex_);
  return map_points_;
}

std::vector<std::shared_ptr<MapPoint>> KeyFrame::valid_map_points() const {
  std::vector<std::shared_ptr<MapPoint>> result;
  std::lock_guard lock(features_mutex_);
  result.reserve(map_points_.size());
  for (const auto& p : map_points_) {
    if (p && !p->is_bad()) result.push_back(p);
  }
  return result;
}

int KeyFrame::tracked_map_points(int min_observations) const {
  int count = 0;
  for (const auto& p : map_points()) {
    if (!p || p->is_bad()) continue;
    if (min_observations <= 0 || p->num_observations() >= min_observations) ++count;
  }
  return count;
}

int KeyFrame::found_map_points(int min_found) const {
  int count = 0;
  for (const auto& p : map_points()) {
    if (p && !p->is_bad() && p->found_count() >= min_found) ++count;
  }
  return count;
}

// ---- covisibility ----
void KeyFrame::update_best_covisibles_locked() {
  ordered_connections_.clear();
  for (const auto& [other_id, link] : connections_)
    ordered_connections_.emplace_back(link.second, link.first);
  std::stable_sort(ordered_connections_.begin(), ordered_connections_.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
}

void KeyFrame::add_connection(const std::shared_ptr<KeyFrame>& other, int weight) {
  std::lock_guard lock(connections_mutex_);
  auto it = connections_.find(other->id);
  if (it != connections_.end() && it->second.second == weight) return;
  connections_[other->id] = {other, weight};
  update_best_covisibles_locked();
}

void KeyFrame::erase_connection(uint64_t other_id) {
  std::lock_guard lock(connections_mutex_);
  if (connections_.erase(other_id) > 0) update_best_covisibles_locked();
}

void KeyFrame::update_connections() {
  constexpr int kEdgeThreshold = 15;
  // Shared points per other keyframe: every observation's keyframe id collected, sorted and counted in
  // runs (ascending ids, as a std::map counter gave them, without a tree lookup per observation).
  std::vector<std::pair<uint64_t, std::weak_ptr<KeyFrame>>> seen;
  const auto points = map_points();
  seen.reserve(points.size() * 4);
  for (const auto& point : points) {
    if (!point || point->is_bad()) continue;
    point->for_each_observation([&](uint64_t kf_id, const MapPoint::Observation& obs) {
      if (kf_id != id) seen.emplace_back(kf_id, obs.keyframe);
    });
  }
  std::sort(seen.begin(), seen.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::pair<uint64_t, std::pair<std::shared_ptr<KeyFrame>, int>>> counter;
  for (size_t i = 0; i < seen.size();) {
    size_t j = i;
    while (j < seen.size() && seen[j].first == seen[i].first) ++j;
    auto kf = seen[i].second.lock();  // keyframes gone or bad are not counted
    if (kf && !kf->is_bad()) counter.push_back({seen[i].first, {std::move(kf), static_cast<int>(j - i)}});
    i = j;
  }
  if (counter.empty()) return;

  std::shared_ptr<KeyFrame> best;
  int best_weight = 0;
  std::vector<std::pair<std::shared_ptr<KeyFrame>, int>> strong;
  for (const auto& [kf_id, entry] : counter) {
    if (entry.second > best_weight) {
      best_weight = entry.second;
      best = entry.first;
    }
    if (entry.second >= kEdgeThreshold) strong.push_back(entry);
  }
  // If no keyframe reaches the threshold, keep the single best edge so the graph stays connected.
  if (strong.empty()) strong.emplace_back(best, best_weight);
  for (const auto& [kf, weight] : strong) kf->add_connection(shared_from_this(), weight);

  std::shared_ptr<KeyFrame> new_parent;
  {
    std::lock_guard lock(connections_mutex_);
    connections_.clear();
    for (const auto& [kf, weight] : strong) connections_[kf->id] = {kf, weight};
    update_best_covisibles_locked();
    if (first_connection_ && id != 0) {
      // Spanning tree: attach to the keyframe sharing most points.
      first_connection_ = false;
      new_parent = ordered_connections_.front().second.lock();
      parent_ = new_parent;
    }
  }
  if (new_parent) new_parent->add_child(shared_from_this());
}

std::vector<std::shared_ptr<KeyFrame>> KeyFrame::connected_keyframes() const {
  return best_covisible(std::numeric_limits<size_t>::max());
}

std::vector<std::shared_ptr<KeyFrame>> KeyFrame::best_covisible(size_t n) const {
  std::lock_guard lock(connections_mutex_);
  std::vector<std::shared_ptr<KeyFrame>> result;
  for (const auto& [weight, weak] : ordered_connections_) {
    if (result.size() >= n) break;
    if (auto kf = weak.lock()) result.push_back(std::move(kf));
  }
  return result;
}

std::vector<std::shared_ptr<KeyFrame>> KeyFrame::covisible_by_weight(int min_weight) const {
  std::lock_guard lock(connections_mutex_);
  std::vector<std::shared_ptr<KeyFrame>> result;
  for (const auto& [weight, weak] : ordered_connections_) {
    if (weight < min_weight) break;
    if (auto kf = weak.lock()) result.push_back(std::move(kf));
  }
  return result;
}

int KeyFrame::weight(uint64_t other_id) const {
  std::lock_guard lock(connections_mutex_);
  auto it = connections_.find(other_id);
  return it == connections_.end() ? 0 : it->second.second;
}

// ---- spanning tree ----
std::shared_ptr<KeyFrame> KeyFrame::parent() const {
  std::lock_guard lock(connections_mutex_);
  return parent_;
}

std::vector<std::shared_ptr<KeyFrame>> KeyFrame::children() const {
  std::lock_guard lock(connections_mutex_);
  std::vector<std::shared_ptr<KeyFrame>> result;
  for (const auto& [child_id, weak] : children_) {
    if (auto kf = weak.lock()) result.push_back(std::move(kf));
  }
  return result;
}

void KeyFrame::add_child(const std::shared_ptr<KeyFrame>& child) {
  std::lock_guard lock(connections_mutex_);
  children_[child->id] = child;
}

void KeyFrame::erase_child(uint64_t child_id) {
  std::lock_guard lock(connections_mutex_);
  children_.erase(child_id);
}

void KeyFrame::change_parent(const std::shared_ptr<KeyFrame>& parent) {
  {
    std::lock_guard lock(connections_mutex_);
    parent_ = parent;
  }
  parent->add_child(shared_from_this());
}

void KeyFrame::restore_parent(const std::shared_ptr<KeyFrame>& parent) {
  {
    std::lock_guard lock(connections_mutex_);
    first_connection_ = false;
    parent_ = parent;
  }
  if (parent) parent->add_child(shared_from_this());
}

void KeyFrame::add_loop_edge(const std::shared_ptr<KeyFrame>& other) {
  std::lock_guard lock(connections_mutex_);
  not_erase_ = true;
  loop_edges_[other->id] = other;
}

std::vector<std::shared_ptr<KeyFrame>> KeyFrame::loop_edges() const {
  std::lock_guard lock(connections_mutex_);
  std::vector<std::shared_ptr<KeyFrame>> result;
  for (const auto& [other_id, weak] : loop_edges_) {
    if (auto kf = weak.lock()) result.push_back(std::move(kf));
  }
  return result;
}

// ---- lifetime ----
bool KeyFrame::is_bad() const { return bad_.load(std::memory_order_acquire); }

void KeyFrame::set_not_erase() {
  std::lock_guard lock(connections_mutex_);
  not_erase_ = true;
}

void KeyFrame::set_erase(Map& map) {
  bool erase_now = false;
  {
    std::lock_guard lock(connections_mutex_);
    if (loop_edges_.empty()) not_erase_ = false;
    erase_now = to_be_erased_ && !not_erase_;
  }
  if (erase_now) set_bad(map);
}

void KeyFrame::set_bad(Map& map) {
  std::vector<std::shared_ptr<KeyFrame>> neighbours;
  {
    std::lock_guard lock(connections_mutex_);
    if (id == 0 || bad_) return;
    if (not_erase_) {
      to_be_erased_ = true;
      return;
    }
    for (const auto& [other_id, link] : connections_) {
      if (auto kf = link.first.lock()) neighbours.push_back(std::move(kf));
    }
  }
  for (const auto& kf : neighbours) kf->erase_connection(id);
  for (size_t i = 0; i < features->size(); ++i) {
    if (auto point = map_point(i)) point->erase_observation(id);
  }

  std::shared_ptr<KeyFrame> my_parent;
  std::vector<std::shared_ptr<KeyFrame>> orphans;
  {
    std::lock_guard lock(connections_mutex_);
    connections_.clear();
    ordered_connections_.clear();
    my_parent = parent_;
    for (const auto& [child_id, weak] : children_) {
      if (auto kf = weak.lock()) orphans.push_back(std::move(kf));
    }
    children_.clear();
  }
  {
    std::lock_guard lock(features_mutex_);
    map_points_.assign(map_points_.size(), nullptr);
  }

  // Spanning tree repair: repeatedly attach the orphan with the strongest covisibility link to a keyframe
  // already in the tree (the parent, or an orphan re-attached before it). Orphans with no such link go
  // to our parent.
  std::set<uint64_t> tree_ids;
  std::vector<std::shared_ptr<KeyFrame>> tree_members;
  if (my_parent) {
    tree_ids.insert(my_parent->id);
    tree_members.push_back(my_parent);
  }
  while (!orphans.empty()) {
    int best_weight = -1;
    size_t best_orphan = 0;
    std::shared_ptr<KeyFrame> best_parent;
    for (size_t i = 0; i < orphans.size(); ++i) {
      for (const auto& candidate : orphans[i]->connected_keyframes()) {
        if (!tree_ids.count(candidate->id)) continue;
        const int w = orphans[i]->weight(candidate->id);
        if (w > best_weight) {
          best_weight = w;
          best_orphan = i;
          best_parent = candidate;
        }
      }
    }
    if (!best_parent) break;
    orphans[best_orphan]->change_parent(best_parent);
    tree_ids.insert(orphans[best_orphan]->id);
    tree_members.push_back(orphans[best_orphan]);
    orphans.erase(orphans.begin() + static_cast<long>(best_orphan));
  }
  if (my_parent) {
    for (const auto& orphan : orphans) orphan->change_parent(my_parent);
    my_parent->erase_child(id);
  }

  const geometry::SE3 cam_from_parent =
      my_parent ? cam_from_world() * my_parent->world_from_cam() : geometry::SE3::identity();
  {
    std::lock_guard lock(connections_mutex_);
    cam_from_parent_ = cam_from_parent;
    bad_ = true;
  }
  map.erase_keyframe(id);
}

void KeyFrame::release_links() {
  {
    std::lock_guard lock(features_mutex_);
    map_points_.assign(map_points_.size(), nullptr);
  }
  std::lock_guard lock(connections_mutex_);
  connections_.clear();
  ordered_connections_.clear();
  children_.clear();
  loop_edges_.clear();
  parent_.reset();
}

geometry::SE3 KeyFrame::cam_from_parent_at_erase() const {
  std::lock_guard lock(connections_mutex_);
  return cam_from_parent_;
}

float KeyFrame::scene_median_depth() const {
  const geometry::SE3 pose = cam_from_world();
  std::vector<double> depths;
  for (const auto& p : valid_map_points()) depths.push_back((pose * p->world()).z());
  if (depths.empty()) return -1.0f;
  std::nth_element(depths.begin(), depths.begin() + static_cast<long>(depths.size() / 2), depths.end());
  return static_cast<float>(depths[depths.size() / 2]);
}

}  // namespace crowdslam::map
