#include "crowdslam/system/map_optimise.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <unordered_map>
#include <vector>

#include "crowdslam/loop/global_ba.h"
#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/mapdb/map_database.h"
#include "crowdslam/optim/bundle_adjustment.h"
#include "crowdslam/util/error.h"

namespace crowdslam::system {

void MapOptimiseOptions::check() const {
  if (iterations < 1) throw InputError("map optimise: --iterations must be >= 1, got " + std::to_string(iterations));
  if (!(ground_sigma >= 0 && ground_sigma <= 1)) {
    throw InputError("map optimise: --ground must be in [0, 1] (a keyframe's height sigma, relative; 0 = off), got " +
                     std::to_string(ground_sigma));
  }
}

namespace {

ReprojectionStats reprojection_stats(const map::Map& map) {
  const double chi2_mono = optim::BundleAdjustmentOptions{}.chi2_mono;  // the threshold BA classifies with
  std::unordered_map<uint64_t, std::shared_ptr<map::KeyFrame>> keyframes;
  for (auto& kf : map.keyframes()) {
    if (!kf->is_bad()) keyframes[kf->id] = kf;
  }
  std::vector<double> errors;
  ReprojectionStats stats;
  double sum2 = 0;
  size_t in_front = 0;
  for (const auto& point : map.map_points()) {
    if (point->is_bad()) continue;
    const geometry::Vec3 world = point->world();
    for (const auto& [kf_id, obs] : point->observations()) {
      const auto it = keyframes.find(kf_id);
      if (it == keyframes.end()) continue;
      const map::KeyFrame& kf = *it->second;
      const auto& key = kf.features->keys_un[obs.index];
      const geometry::Vec3 c = kf.cam_from_world() * world;
      const double e2 = c.z() <= 0 ? std::numeric_limits<double>::infinity()
                                   : (kf.camera->project(c) - geometry::Vec2(key.pt.x, key.pt.y)).squaredNorm();
      errors.push_back(std::sqrt(e2));
      if (std::isfinite(e2)) {
        sum2 += e2;
        ++in_front;
      }
      if (!(e2 * kf.levels->inv_sigma2[key.octave] <= chi2_mono)) ++stats.above_chi2;
    }
  }
  stats.observations = errors.size();
  if (errors.empty()) return stats;
  stats.rms_px = in_front ? std::sqrt(sum2 / static_cast<double>(in_front)) : 0.0;
  auto mid = errors.begin() + static_cast<std::ptrdiff_t>(errors.size() / 2);
  std::nth_element(errors.begin(), mid, errors.end());
  stats.median_px = *mid;
  return stats;
}

}  // namespace

MapOptimiseReport optimise_saved_map(const std::filesystem::path& input, const std::filesystem::path& output,
                                     const MapOptimiseOptions& options) {
  options.check();
  if (std::filesystem::exists(output) && !options.overwrite) {
    throw InputError(output.string() + ": map optimise: the output exists; pass --overwrite to replace it");
  }
  const auto start = std::chrono::steady_clock::now();
  const mapdb::MapHeader header = mapdb::read_map_header(input);
  const auto& id = header.identity;
  auto camera = std::make_shared<const geometry::PinholeCamera>(id.camera);
  auto levels = std::make_shared<const map::ScaleLevels>(static_cast<float>(id.orb_scale_factor), id.orb_levels);
  auto map = std::make_shared<map::Map>();
  mapdb::load_map(input, id, *map, camera, levels, nullptr);

  MapOptimiseReport report;
  report.keyframes = map->num_keyframes();
  report.map_points = map->num_map_points();
  if (report.keyframes < 2) {
    throw InputError(input.string() + ": map optimise: the map has " + std::to_string(report.keyframes) +
                     " keyframe(s); bundle adjustment needs two");
  }
  report.before = reprojection_stats(*map);
  loop::GlobalBundleAdjuster adjuster(map, nullptr, options.iterations);
  if (options.ground_sigma > 0) {
    geometry::GroundPlaneOptions ground;
    ground.keyframe_sigma = options.ground_sigma;
    adjuster.set_ground(ground);
  }
  if (!adjuster.run()) throw InputError(input.string() + ": map optimise: the map has no points to optimise");
  const auto stats = adjuster.stats();
  report.iterations = stats.last_iterations;
  report.initial_cost = stats.last_initial_cost;
  report.final_cost = stats.last_final_cost;
  report.keyframes_with_ground = stats.ground_keyframes;
  report.ground_points = stats.ground_points;
  report.after = reprojection_stats(*map);
  mapdb::save_map(output, *map, header);
  report.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace crowdslam::system
