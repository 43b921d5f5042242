#include "crowdslam/loop/global_ba.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <unordered_map>

#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/util/thread_priority.h"

namespace crowdslam::loop {

GlobalBundleAdjuster::GlobalBundleAdjuster(std::shared_ptr<map::Map> map, LocalMappingControl* mapper,
                                           int iterations)
    : map_(std::move(map)), mapper_(mapper), iterations_(iterations) {}

GlobalBundleAdjuster::~GlobalBundleAdjuster() { abort(); }

void GlobalBundleAdjuster::set_ground(const geometry::GroundPlaneOptions& options) {
  options.check();
  ground_ = options;
}

void GlobalBundleAdjuster::launch() {
  abort();
  abort_ = false;
  running_ = true;
  worker_ = std::thread([this] {
    util::set_thread_name("cs-global-ba");
    optimise_and_apply();
    running_ = false;
  });
}

bool GlobalBundleAdjuster::run() {
  abort();
  abort_ = false;
  running_ = true;
  const bool applied = optimise_and_apply();
  running_ = false;
  return applied;
}

void GlobalBundleAdjuster::abort() {
  abort_ = true;
  if (worker_.joinable()) worker_.join();
}

void GlobalBundleAdjuster::wait() {
  if (worker_.joinable()) worker_.join();
}

GlobalBaStats GlobalBundleAdjuster::stats() const {
  std::lock_guard lock(stats_mutex_);
  return stats_;
}

namespace {

// Spanning-tree order from the roots: every keyframe after its parent.
std::vector<std::shared_ptr<map::KeyFrame>> tree_order(const std::vector<std::shared_ptr<map::KeyFrame>>& keyframes) {
  std::vector<std::shared_ptr<map::KeyFrame>> order;
  std::unordered_map<uint64_t, bool> seen;
  std::deque<std::shared_ptr<map::KeyFrame>> queue;
  for (const auto& kf : keyframes) {
    auto parent = kf->parent();
    if (!parent || parent->is_bad()) queue.push_back(kf);
  }
  while (!queue.empty()) {
    auto kf = queue.front();
    queue.pop_front();
    if (seen[kf->id]) continue;
    seen[kf->id] = true;
    order.push_back(kf);
    for (auto& child : kf->children()) {
      if (!child->is_bad()) queue.push_back(child);
    }
  }
  for (const auto& kf : keyframes) {  // anything the tree did not reach (should not happen)
    if (!seen[kf->id]) order.push_back(kf);
  }
  return order;
}

}  // namespace

std::vector<optim::BaPlaneConstraint> GlobalBundleAdjuster::ground_constraints(
    const std::vector<std::shared_ptr<map::KeyFrame>>& keyframes, const std::vector<std::shared_ptr<map::MapPoint>>& points) {
  std::unordered_map<const map::MapPoint*, int> point_index;
  for (size_t k = 0; k < points.size(); ++k) point_index[points[k].get()] = static_cast<int>(k);
  // Each keyframe's points in its camera frame, and their index among `points`.
  std::vector<std::vector<geometry::Vec3>> in_camera(keyframes.size());
  std::vector<std::vector<int>> index(keyframes.size());
  for (size_t i = 0; i < keyframes.size(); ++i) {
    const geometry::SE3 cam_from_world = keyframes[i]->cam_from_world();
    for (const auto& p : keyframes[i]->valid_map_points()) {
      const auto it = point_index.find(p.get());
      if (it == point_index.end()) continue;
      in_camera[i].push_back(cam_from_world * p->world());
      index[i].push_back(it->second);
    }
  }
  std::vector<optim::BaPlaneConstraint> planes;
  const auto ground = geometry::estimate_ground(in_camera, *ground_);
  if (ground) {
    for (size_t i = 0; i < keyframes.size(); ++i) {
      const auto& plane = ground->planes[i];
      if (!plane) continue;
      // n points at sigma * sqrt(n) each: the keyframe's height at keyframe_sigma, however many it has.
      const double sigma =
          ground_->keyframe_sigma * std::sqrt(static_cast<double>(plane->inliers.size())) * ground->height;
      for (size_t j : plane->inliers) planes.push_back({static_cast<int>(i), index[i][j], plane->normal, ground->height, sigma});
    }
  }
  const int with_ground = ground ? ground->keyframes_with_ground() : 0;
  spdlog::info("global BA: the ground under {} of {} keyframes ({} points)", with_ground, keyframes.size(), planes.size());
  std::lock_guard lock(stats_mutex_);
  stats_.ground_keyframes = with_ground;
  stats_.ground_points = static_cast<int>(planes.size());
  stats_.ground_height = ground ? ground->height : 0.0;
  return planes;
}

bool GlobalBundleAdjuster::optimise_and_apply() {
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::shared_ptr<map::KeyFrame>> keyframes;
  for (auto& kf : map_->keyframes()) {
    if (!kf->is_bad()) keyframes.push_back(std::move(kf));
  }
  std::vector<std::shared_ptr<map::MapPoint>> points;
  for (auto& p : map_->map_points()) {
    if (!p->is_bad()) points.push_back(std::move(p));
  }
  if (keyframes.size() < 2 || points.empty()) return false;

  std::unordered_map<uint64_t, size_t> keyframe_index;
  std::vector<optim::BaKeyframe> ba_keyframes;
  for (size_t i = 0; i < keyframes.size(); ++i) {
    keyframe_index[keyframes[i]->id] = i;
    ba_keyframes.push_back({static_cast<int>(i), keyframes[i]->cam_from_world(), i == 0});
  }
  std::vector<optim::BaPoint> ba_points;
  std::vector<optim::BaObservation> observations;
  ba_points.reserve(points.size());
  for (size_t k = 0; k < points.size(); ++k) {
    ba_points.push_back({static_cast<int>(k), points[k]->world()});
    for (const auto& [kf_id, obs] : points[k]->observations()) {
      const auto it = keyframe_index.find(kf_id);
      if (it == keyframe_index.end()) continue;
      const map::KeyFrame& kf = *keyframes[it->second];
      const auto& f = *kf.features;
      const auto& key = f.keys_un[obs.index];
      optim::BaObservation o;
      o.keyframe_id = static_cast<int>(it->second);
      o.point_id = static_cast<int>(k);
      o.pixel = geometry::Vec2(key.pt.x, key.pt.y);
      o.right_u = f.right_u[obs.index];
      o.inv_sigma2 = kf.levels->inv_sigma2[key.octave];
      observations.push_back(o);
    }
  }
  std::vector<optim::BaPlaneConstraint> planes;
  if (ground_) planes = ground_constraints(keyframes, points);
  optim::BundleAdjustmentOptions options;
  options.first_pass_iterations = iterations_;
  options.second_pass_iterations = 0;
  options.num_threads = 1;
  const auto result = optim::local_bundle_adjustment(*keyframes.front()->camera, ba_keyframes, ba_points,
                                                     observations, options, &abort_, planes);
  const double optimise_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (result.aborted || abort_) {
    std::lock_guard lock(stats_mutex_);
    ++stats_.runs;
    ++stats_.aborted;
    stats_.time_ms_total += optimise_ms;
    return false;
  }

  if (mapper_) {
    mapper_->request_pause();
    mapper_->wait_until_paused();
  }
  {
    std::lock_guard map_lock(map_->update_mutex());
    // Keyframes: optimised ones take their new pose; newer ones follow their parent rigidly.
    std::unordered_map<uint64_t, geometry::SE3> before;
    std::unordered_map<uint64_t, geometry::SE3> after;
    std::vector<std::shared_ptr<map::KeyFrame>> current;
    for (auto& kf : map_->keyframes()) {
      if (!kf->is_bad()) current.push_back(std::move(kf));
    }
    for (const auto& kf : tree_order(current)) {
      const geometry::SE3 old_pose = kf->cam_from_world();
      geometry::SE3 new_pose = old_pose;
      if (const auto it = keyframe_index.find(kf->id); it != keyframe_index.end()) {
        new_pose = result.keyframes[it->second].cam_from_world;
      } else if (auto parent = kf->parent(); parent && after.count(parent->id)) {
        new_pose = old_pose * before.at(parent->id).inverse() * after.at(parent->id);
      }
      before[kf->id] = old_pose;
      after[kf->id] = new_pose;
      kf->set_cam_from_world(new_pose);
    }
    // Points: optimised ones take their new position; newer ones move with their reference keyframe.
    std::unordered_map<uint64_t, size_t> point_index;
    for (size_t k = 0; k < points.size(); ++k) point_index[points[k]->id] = k;
    for (const auto& point : map_->map_points()) {
      if (point->is_bad()) continue;
      if (const auto it = point_index.find(point->id); it != point_index.end()) {
        point->set_world(result.points[it->second].world);
      } else {
        const auto reference = point->reference_keyframe();
        if (!reference || !before.count(reference->id)) continue;
        point->set_world(after.at(reference->id).inverse() * (before.at(reference->id) * point->world()));
      }
      point->update_normal_and_depth();
    }
  }
  map_->notify_big_change();
  if (mapper_) mapper_->resume();
  const double total_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  spdlog::info("global BA: {} keyframes, {} points, {:.0f} ms", keyframes.size(), points.size(), total_ms);
  std::lock_guard lock(stats_mutex_);
  ++stats_.runs;
  ++stats_.applied;
  stats_.time_ms_total += total_ms;
  stats_.last_initial_cost = result.initial_cost;
  stats_.last_final_cost = result.final_cost;
  stats_.last_iterations = result.iterations;
  return true;
}

}  // namespace crowdslam::loop
