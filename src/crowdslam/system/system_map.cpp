// System: saving the map and loading a saved one (mapdb/).
#include <spdlog/spdlog.h>

#include <chrono>

#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/system/system.h"
#include "crowdslam/util/error.h"

namespace crowdslam::system {

mapdb::MapIdentity System::map_identity() const {
  mapdb::MapIdentity id;
  id.sensor = io::to_string(options_.sensor);
  id.camera = *camera_;
  id.depth_map_factor = options_.sensor == io::SensorKind::kRgbd ? settings_.depth_map_factor : 0.0;
  id.orb_features = settings_.orb.n_features;
  id.orb_scale_factor = settings_.orb.scale_factor;
  id.orb_levels = settings_.orb.n_levels;
  if (vocabulary_) {
    id.vocabulary_hash = mapdb::vocabulary_hash(*vocabulary_);
    id.vocabulary_words = vocabulary_->num_words();
  }
  return id;
}

mapdb::LoadedMap System::load_map(const std::string& path, bool localization_only) {
  if (next_frame_id_ > 0) throw InputError(path + ": a map can only be loaded before the first frame");
  if (!vocabulary_) {
    throw InputError(path + ": loading a map needs a vocabulary (relocalisation into it uses the keyframe database)");
  }
  const auto start = std::chrono::steady_clock::now();
  auto loaded = mapdb::load_map(path, map_identity(), *map_, camera_, frame_builder_->levels(), vocabulary_.get());
  for (const auto& kf : loaded.keyframes) keyframe_database_->add(kf);
  tracker_->start_in_loaded_map(localization_only);
  loaded_map_origin_ = loaded.header.origin;
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  spdlog::info("map {}: {} keyframes, {} points loaded in {:.0f} ms ({})", path, loaded.keyframes.size(),
               loaded.map_points, ms, localization_only ? "localisation only" : "continue mapping");
  return loaded;
}

void System::save_map(const std::string& path, const mapdb::MapOrigin& origin) const {
  mapdb::MapHeader header;
  header.identity = map_identity();
  header.origin = loaded_map_origin_ ? *loaded_map_origin_ : origin;
  mapdb::save_map(path, *map_, header);
}

}  // namespace crowdslam::system

namespace crowdslam::system {

void System::publish_map_snapshot(bool force) {
  double interval = 0;
  for (auto* observer : observers_) {
    const double wanted = observer->map_snapshot_interval_s();
    if (wanted > 0 && (interval == 0 || wanted < interval)) interval = wanted;
  }
  if (interval == 0) return;
  const auto now = std::chrono::steady_clock::now();
  if (!force && last_snapshot_ && std::chrono::duration<double>(now - *last_snapshot_).count() < interval) return;
  last_snapshot_ = now;
  const auto snapshot = take_map_snapshot();
  for (auto* observer : observers_) {
    if (observer->map_snapshot_interval_s() > 0) observer->on_map_snapshot(snapshot);
  }
}

std::shared_ptr<const MapSnapshot> System::take_map_snapshot() const {
  auto snapshot = std::make_shared<MapSnapshot>();
  snapshot->frame_index = next_frame_id_ > 0 ? next_frame_id_ - 1 : 0;
  snapshot->map_id = map_resets_;
  std::lock_guard lock(map_->update_mutex());  // no half-applied bundle adjustment
  const auto keyframes = map_->keyframes();
  snapshot->keyframes.reserve(keyframes.size());
  for (const auto& kf : keyframes) {
    if (kf->is_bad()) continue;
    snapshot->keyframes.push_back({kf->id, kf->timestamp_s, kf->world_from_cam()});
    for (const auto& other : kf->covisible_by_weight(100)) {
      if (other->id > kf->id) snapshot->covisibility.emplace_back(kf->id, other->id);
    }
    for (const auto& other : kf->loop_edges()) {
      if (other->id > kf->id) snapshot->loop_edges.emplace_back(kf->id, other->id);
    }
  }
  const auto points = map_->map_points();
  snapshot->points.reserve(points.size());
  for (const auto& point : points) {
    if (point->is_bad()) continue;
    const auto w = point->world();
    snapshot->points.push_back({point->id, static_cast<float>(w.x()), static_cast<float>(w.y()),
                                static_cast<float>(w.z()), point->num_observations()});
  }
  snapshot->loops_closed = loop_closer_ ? static_cast<int>(loop_closer_->stats().loops.size()) : 0;
  return snapshot;
}

}  // namespace crowdslam::system
