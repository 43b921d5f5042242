// Local mapping step: erase keyframes whose points are almost all seen, at the same or a finer scale,
// by at least three other keyframes (ORB-SLAM's 90% rule).
#include "crowdslam/map/map_point.h"
#include "crowdslam/mapping/local_mapper.h"

namespace crowdslam::mapping {

void LocalMapper::cull_keyframes(const std::shared_ptr<map::KeyFrame>& keyframe) {
  constexpr int kOtherObservers = 3;
  int culled = 0;
  for (const auto& candidate : keyframe->connected_keyframes()) {
    if (candidate->id == 0 || candidate->is_bad()) continue;
    const auto& f = *candidate->features;
    const auto points = candidate->map_points();
    int total = 0;
    int redundant = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      const auto& point = points[i];
      if (!point || point->is_bad()) continue;
      if (!options_.monocular && (f.depth_m[i] > options_.close_depth_m || f.depth_m[i] < 0)) continue;
      ++total;
      if (point->num_observations() <= kOtherObservers) continue;
      const int level = f.keys_un[i].octave;
      int observers = 0;
      point->for_each_observation([&](uint64_t kf_id, const map::MapPoint::Observation& obs) {
        if (kf_id == candidate->id || observers >= kOtherObservers) return;
        auto other = obs.keyframe.lock();
        if (other && other->features->keys_un[obs.index].octave <= level + 1) ++observers;
      });
      if (observers >= kOtherObservers) ++redundant;
    }
    if (total > 0 && redundant > options_.redundancy_ratio * total) {
      candidate->set_bad(*map_);
      ++culled;
    }
  }
  std::lock_guard lock(stats_mutex_);
  stats_.keyframes_culled += culled;
}

}  // namespace crowdslam::mapping
