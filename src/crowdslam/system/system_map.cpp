// System: saving the map and loading a saved one (mapdb/).
#include <spdlog/spdlog.h>

#include <chrono>

#include "crowdslam/map/keyframe.h"
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
