// Local mapping step: local bundle adjustment over the new keyframe's covisibility neighbourhood.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "crowdslam/map/map_point.h"
#include "crowdslam/mapping/local_mapper.h"

namespace crowdslam::mapping {

void LocalMapper::run_local_bundle_adjustment(const std::shared_ptr<map::KeyFrame>& keyframe) {
  const auto start = std::chrono::steady_clock::now();
  // Local window: the keyframe and its covisible keyframes; their points; fixed: other keyframes that see
  // those points.
  std::vector<std::shared_ptr<map::KeyFrame>> local{keyframe};
  std::unordered_set<uint64_t> local_ids{keyframe->id};
  for (const auto& kf : keyframe->best_covisible(static_cast<size_t>(options_.max_local_ba_keyframes))) {
    if (!kf->is_bad() && local_ids.insert(kf->id).second) local.push_back(kf);
  }
  std::vector<std::shared_ptr<map::MapPoint>> points;
  std::unordered_set<uint64_t> point_ids;
  for (const auto& kf : local) {
    for (auto& p : kf->valid_map_points()) {
      if (point_ids.insert(p->id).second) points.push_back(std::move(p));
    }
  }
  std::unordered_map<uint64_t, std::shared_ptr<map::KeyFrame>> all_keyframes;
  for (const auto& kf : local) all_keyframes[kf->id] = kf;
  // Fixed keyframes: those outside the window that see the most of its points, at most
  // max_local_ba_keyframes of them (observations from the others are left out).
  std::unordered_set<uint64_t> fixed_ids;
  {
    std::unordered_map<uint64_t, int> seen_points;
    for (const auto& point : points) {
      point->for_each_observation([&](uint64_t kf_id, const map::MapPoint::Observation&) {
        if (!local_ids.count(kf_id)) ++seen_points[kf_id];
      });
    }
    std::vector<std::pair<int, uint64_t>> by_count;
    for (const auto& [kf_id, count] : seen_points) by_count.emplace_back(count, kf_id);
    const size_t keep = std::min(by_count.size(), static_cast<size_t>(options_.max_local_ba_keyframes));
    std::partial_sort(by_count.begin(), by_count.begin() + static_cast<std::ptrdiff_t>(keep), by_count.end(),
                      [](const auto& a, const auto& b) { return a.first > b.first || (a.first == b.first && a.second < b.second); });
    for (size_t i = 0; i < keep; ++i) fixed_ids.insert(by_count[i].second);
  }

  std::vector<optim::BaObservation> observations;
  struct Link {
    std::shared_ptr<map::KeyFrame> keyframe;
    std::shared_ptr<map::MapPoint> point;
    size_t index;
  };
  std::vector<Link> links;
  std::vector<optim::BaPoint> ba_points;
  ba_points.reserve(points.size());
  for (size_t k = 0; k < points.size(); ++k) {
    const auto& point = points[k];
    ba_points.push_back({static_cast<int>(k), point->world()});
    point->for_each_observation([&](uint64_t kf_id, const map::MapPoint::Observation& obs) {
      if (!local_ids.count(kf_id) && !fixed_ids.count(kf_id)) return;
      auto kf = obs.keyframe.lock();
      if (!kf || kf->is_bad()) return;
      all_keyframes.emplace(kf_id, kf);  // fixed if not local
      const auto& f = *kf->features;
      optim::BaObservation o;
      o.keyframe_id = static_cast<int>(kf_id);
      o.point_id = static_cast<int>(k);
      o.pixel = geometry::Vec2(f.keys_un[obs.index].pt.x, f.keys_un[obs.index].pt.y);
      o.right_u = f.right_u[obs.index];
      o.inv_sigma2 = kf->levels->inv_sigma2[f.keys_un[obs.index].octave];
      observations.push_back(o);
      links.push_back({std::move(kf), point, obs.index});
    });
  }
  std::vector<optim::BaKeyframe> ba_keyframes;
  std::vector<std::shared_ptr<map::KeyFrame>> ba_keyframe_refs;
  for (const auto& [id, kf] : all_keyframes) {
    ba_keyframes.push_back({static_cast<int>(id), kf->cam_from_world(), !local_ids.count(id) || id == 0});
    ba_keyframe_refs.push_back(kf);
  }
  // Gauge: with no fixed keyframe (a young map), keep the oldest one fixed.
  bool any_fixed = false;
  for (const auto& k : ba_keyframes) any_fixed = any_fixed || k.fixed;
  if (!any_fixed && !ba_keyframes.empty()) {
    size_t oldest = 0;
    for (size_t i = 1; i < ba_keyframes.size(); ++i) {
      if (ba_keyframes[i].id < ba_keyframes[oldest].id) oldest = i;
    }
    ba_keyframes[oldest].fixed = true;
  }
  if (abort_ba_) return;

  // Tracked relative poses between keyframes of the adjustment (KeyFrame::odometry).
  std::vector<optim::BaRelativePose> relative_poses;
  if (options_.odometry_sigma_deg > 0) {
    const double sigma_rad = options_.odometry_sigma_deg * M_PI / 180.0;
    for (const auto& [id, kf] : all_keyframes) {
      if (!kf->odometry || !all_keyframes.count(kf->odometry->other_id)) continue;
      if (!local_ids.count(id) && !local_ids.count(kf->odometry->other_id)) continue;  // both fixed
      optim::BaRelativePose edge;
      edge.keyframe_id = static_cast<int>(id);
      edge.other_id = static_cast<int>(kf->odometry->other_id);
      edge.cam_from_other = kf->odometry->cam_from_other;
      edge.rotation_sigma_rad = sigma_rad;
      edge.translation_sigma = sigma_rad * kf->odometry->median_depth;
      relative_poses.push_back(edge);
    }
  }
  const auto result = optim::local_bundle_adjustment(*keyframe->camera, ba_keyframes, ba_points, observations,
                                                     options_.ba, &abort_ba_, {}, relative_poses);
  {
    std::lock_guard map_lock(map_->update_mutex());
    for (size_t index : result.outliers) {
      const Link& link = links[index];
      if (link.keyframe->map_point(link.index) == link.point) link.keyframe->erase_map_point(link.index);
      link.point->erase_observation(link.keyframe->id);
    }
    for (size_t i = 0; i < result.keyframes.size(); ++i) {
      if (!ba_keyframes[i].fixed) ba_keyframe_refs[i]->set_cam_from_world(result.keyframes[i].cam_from_world);
    }
    for (size_t k = 0; k < result.points.size(); ++k) {
      if (points[k]->is_bad()) continue;
      points[k]->set_world(result.points[k].world);
      points[k]->update_normal_and_depth();
    }
  }
  const double elapsed_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::lock_guard lock(stats_mutex_);
  ++stats_.ba_runs;
  stats_.ba_relative_poses += static_cast<int>(relative_poses.size());
  if (result.aborted) ++stats_.ba_aborted;
  stats_.ba_time_ms_total += elapsed_ms;
}

}  // namespace crowdslam::mapping
