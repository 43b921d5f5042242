#include "crowdslam/mapping/local_mapper.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <unordered_set>

#include "crowdslam/loop/keyframe_database.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/match/orb_matcher.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/thread_priority.h"

namespace crowdslam::mapping {

void LocalMapperOptions::check() const {
  if (!(close_depth_m > 0)) throw InputError("local mapper: close depth must be > 0");
  if (max_local_ba_keyframes < 1) throw InputError("local mapper: max_local_ba_keyframes must be >= 1");
  if (triangulation_neighbours < 1) throw InputError("local mapper: triangulation_neighbours must be >= 1");
  if (!(redundancy_ratio > 0 && redundancy_ratio <= 1))
    throw InputError("local mapper: redundancy_ratio in (0, 1]");
  if (!(delay_ms >= 0)) throw InputError("local mapper: delay_ms must be >= 0");
  if (!(odometry_sigma_deg >= 0)) throw InputError("local mapper: odometry_sigma_deg must be >= 0");
  ba.check();
}

LocalMapper::LocalMapper(const LocalMapperOptions& options, std::shared_ptr<map::Map> map)
    : options_(options), map_(std::move(map)) {
  options_.check();
}

LocalMapper::~LocalMapper() { stop(); }

void LocalMapper::start() {
  if (worker_.joinable()) return;
  {
    std::lock_guard lock(queue_mutex_);
    stop_requested_ = false;
    worker_active_ = true;
  }
  worker_ = std::thread([this] {
    util::set_thread_name("cs-mapper");
    util::lower_thread_priority(options_.thread_nice);
    run();
    std::lock_guard lock(queue_mutex_);
    worker_active_ = false;
    paused_cv_.notify_all();
    idle_cv_.notify_all();
  });
}

void LocalMapper::stop() {
  {
    std::lock_guard lock(queue_mutex_);
    stop_requested_ = true;
  }
  queue_cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void LocalMapper::stop_now() {
  size_t dropped = 0;
  {
    std::lock_guard lock(queue_mutex_);
    stop_requested_ = true;
    stopping_now_ = true;
    dropped = queue_.size();
    queue_.clear();
    abort_ba_ = true;
  }
  queue_cv_.notify_all();
  if (worker_.joinable()) worker_.join();
  if (dropped > 0) spdlog::info("local mapping stopped: {} queued keyframes not processed", dropped);
}

void LocalMapper::run() {
  while (true) {
    std::shared_ptr<map::KeyFrame> keyframe;
    {
      std::unique_lock lock(queue_mutex_);
      accepting_ = true;
      if (queue_.empty()) idle_cv_.notify_all();
      queue_cv_.wait(lock, [this] { return stop_requested_ || !queue_.empty() || pause_requested_; });
      if (pause_requested_) {  // loop correction or global BA: wait here until resumed
        paused_ = true;
        paused_cv_.notify_all();
        idle_cv_.notify_all();
        queue_cv_.wait(lock, [this] { return !pause_requested_; });
        paused_ = false;
        continue;
      }
      if (queue_.empty()) return;  // stop requested and nothing left to do
      accepting_ = false;
      keyframe = queue_.front();
      queue_.pop_front();
    }
    process_keyframe(keyframe);
  }
}

void LocalMapper::process_all() {
  while (auto keyframe = next_keyframe()) process_keyframe(keyframe);
}

std::shared_ptr<map::KeyFrame> LocalMapper::next_keyframe() {
  std::lock_guard lock(queue_mutex_);
  if (queue_.empty()) return nullptr;
  auto keyframe = queue_.front();
  queue_.pop_front();
  return keyframe;
}

void LocalMapper::request_pause() {
  {
    std::lock_guard lock(queue_mutex_);
    pause_requested_ = true;
    abort_ba_ = true;
  }
  queue_cv_.notify_all();
}

void LocalMapper::wait_until_paused() {
  std::unique_lock lock(queue_mutex_);
  // Sequential mode (no worker): the mapper runs inline on the caller's thread, so it is idle now.
  paused_cv_.wait(lock, [this] { return paused_ || !pause_requested_ || !worker_active_; });
}

void LocalMapper::resume() {
  {
    std::lock_guard lock(queue_mutex_);
    pause_requested_ = false;
  }
  queue_cv_.notify_all();
  paused_cv_.notify_all();
}

void LocalMapper::insert_keyframe(std::shared_ptr<map::KeyFrame> keyframe) {
  {
    std::lock_guard lock(queue_mutex_);
    queue_.push_back(std::move(keyframe));
    abort_ba_ = true;
  }
  queue_cv_.notify_one();
}

void LocalMapper::insert_keyframes(std::shared_ptr<map::KeyFrame> first, std::shared_ptr<map::KeyFrame> second) {
  {
    std::lock_guard lock(queue_mutex_);
    queue_.push_back(std::move(first));
    queue_.push_back(std::move(second));
    abort_ba_ = true;
  }
  queue_cv_.notify_one();
}

bool LocalMapper::accepts_keyframes() const { return accepting_ && queued_keyframes() == 0; }

size_t LocalMapper::queued_keyframes() const {
  std::lock_guard lock(queue_mutex_);
  return queue_.size();
}

bool LocalMapper::wait_until_accepting(double timeout_ms) {
  std::unique_lock lock(queue_mutex_);
  // Sequential mode (no worker): keyframes are processed inline, so the mapper is idle whenever asked.
  idle_cv_.wait_for(lock, std::chrono::duration<double, std::milli>(timeout_ms),
                    [this] { return idle_or_not_working(); });
  return accepting_ && queue_.empty();
}

bool LocalMapper::idle_or_not_working() const {
  return (accepting_ && queue_.empty()) || !worker_active_ || stop_requested_ || pause_requested_;
}

bool LocalMapper::has_new_keyframes() const { return queued_keyframes() > 0; }

void LocalMapper::interrupt_bundle_adjustment() { abort_ba_ = true; }

void LocalMapper::reset() {
  {
    std::lock_guard lock(queue_mutex_);
    queue_.clear();
  }
  recent_points_.clear();
}

LocalMapperStats LocalMapper::stats() const {
  std::lock_guard lock(stats_mutex_);
  return stats_;
}

void LocalMapper::process_keyframe(const std::shared_ptr<map::KeyFrame>& keyframe) {
  using Clock = std::chrono::steady_clock;
  const auto ms_since = [](Clock::time_point t) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
  };
  const auto start = Clock::now();
  if (options_.delay_ms > 0)
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(options_.delay_ms));
  register_keyframe(keyframe);
  cull_recent_points(keyframe);
  const double register_ms = ms_since(start);
  auto t = Clock::now();
  create_new_points(keyframe);
  const double triangulation_ms = ms_since(t);
  t = Clock::now();
  if (!has_new_keyframes()) fuse_with_neighbours(keyframe);
  const double fusion_ms = ms_since(t);
  abort_ba_ = false;
  double culling_ms = 0;
  double ba_ms = 0;
  if (!has_new_keyframes() && !pause_requested_ && !stopping_now_) {
    t = Clock::now();
    if (options_.local_ba && map_->num_keyframes() > 2) run_local_bundle_adjustment(keyframe);
    ba_ms = ms_since(t);
    t = Clock::now();
    cull_keyframes(keyframe);
    culling_ms = ms_since(t);
  }
  map_->erase_bad_map_points();
  // Place recognition sees the keyframe only once it is registered in the map.
  if (database_ && keyframe->features->has_bow() && !keyframe->is_bad()) database_->add(keyframe);
  if (keyframe_done_ && !keyframe->is_bad()) keyframe_done_(keyframe);
  std::lock_guard lock(stats_mutex_);
  ++stats_.keyframes_processed;
  stats_.register_ms_total += register_ms;
  stats_.triangulation_ms_total += triangulation_ms;
  stats_.fusion_ms_total += fusion_ms;
  stats_.culling_ms_total += culling_ms;
  const double total_ms = ms_since(start);
  stats_.processing_ms_total += total_ms;
  stats_.per_keyframe.push_back({register_ms, triangulation_ms, fusion_ms, ba_ms, culling_ms, total_ms});
}

void LocalMapper::register_keyframe(const std::shared_ptr<map::KeyFrame>& keyframe) {
  const auto points = keyframe->map_points();
  for (size_t i = 0; i < points.size(); ++i) {
    const auto& point = points[i];
    if (!point || point->is_bad()) continue;
    if (!point->is_observed_by(keyframe->id)) {
      point->add_observation(keyframe, i);
      point->update_normal_and_depth();
      point->compute_distinctive_descriptor();
    } else {
      // Created by tracking for this keyframe (from depth): check it in the next keyframes.
      recent_points_.push_back(point);
    }
  }
  keyframe->update_connections();
  map_->add_keyframe(keyframe);
}

void LocalMapper::cull_recent_points(const std::shared_ptr<map::KeyFrame>& keyframe) {
  const int observation_threshold = options_.monocular ? 2 : 3;
  int culled = 0;
  std::vector<std::shared_ptr<map::MapPoint>> kept;
  kept.reserve(recent_points_.size());
  for (auto& point : recent_points_) {
    if (point->is_bad()) continue;
    const uint64_t age = keyframe->id - point->first_keyframe_id;
    if (point->found_ratio() < 0.25f) {
      point->set_bad();
      ++culled;
    } else if (age >= 2 && point->num_observations() <= observation_threshold) {
      point->set_bad();
      ++culled;
    } else if (age < 3) {
      kept.push_back(std::move(point));
    }
  }
  recent_points_.swap(kept);
  std::lock_guard lock(stats_mutex_);
  stats_.points_culled += culled;
}

void LocalMapper::fuse_with_neighbours(const std::shared_ptr<map::KeyFrame>& keyframe) {
  const size_t first_ring = options_.monocular ? 20 : 10;
  std::vector<std::shared_ptr<map::KeyFrame>> targets;
  std::unordered_set<uint64_t> included{keyframe->id};
  for (const auto& neighbour : keyframe->best_covisible(first_ring)) {
    if (neighbour->is_bad() || !included.insert(neighbour->id).second) continue;
    targets.push_back(neighbour);
    for (const auto& second : neighbour->best_covisible(5)) {
      if (second->is_bad() || !included.insert(second->id).second) continue;
      targets.push_back(second);
    }
  }
  // Current keyframe's points into the neighbours...
  const auto own_points = keyframe->valid_map_points();
  for (const auto& target : targets) match::fuse(target, own_points);
  // ...and the neighbours' points into the current keyframe.
  std::vector<std::shared_ptr<map::MapPoint>> candidates;
  std::unordered_set<uint64_t> seen;
  for (const auto& target : targets) {
    for (auto& point : target->valid_map_points()) {
      if (seen.insert(point->id).second) candidates.push_back(std::move(point));
    }
  }
  match::fuse(keyframe, candidates);

  for (const auto& point : keyframe->valid_map_points()) {
    point->compute_distinctive_descriptor();
    point->update_normal_and_depth();
  }
  keyframe->update_connections();
}

}  // namespace crowdslam::mapping
