// Local mapping step: triangulate new map points between the new keyframe and its covisible neighbours.
#include <cmath>

#include "crowdslam/geometry/triangulation.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/mapping/local_mapper.h"
#include "crowdslam/match/orb_matcher.h"

namespace crowdslam::mapping {

namespace {

struct View {
  const map::KeyFrame& keyframe;
  geometry::SE3 cam_from_world;
  geometry::Vec3 centre;
};

geometry::Vec2 pixel_of(const map::KeyFrame& kf, size_t i) {
  return {kf.features->keys_un[i].pt.x, kf.features->keys_un[i].pt.y};
}

// The 3D point for one match, or nullopt when the geometry is not good enough.
std::optional<geometry::Vec3> triangulate_match(const View& v1, size_t i1, const View& v2, size_t i2) {
  const auto& f1 = *v1.keyframe.features;
  const auto& f2 = *v2.keyframe.features;
  const auto& cam1 = *v1.keyframe.camera;
  const auto& cam2 = *v2.keyframe.camera;
  const geometry::Vec2 px1 = pixel_of(v1.keyframe, i1);
  const geometry::Vec2 px2 = pixel_of(v2.keyframe, i2);
  const geometry::Vec2 n1 = cam1.normalize(px1);
  const geometry::Vec2 n2 = cam2.normalize(px2);
  const double cos_rays = geometry::ray_parallax_cosine(v1.cam_from_world, n1, v2.cam_from_world, n2);

  // Parallax a depth measurement gives (the angle the stereo baseline subtends at that depth).
  const bool stereo1 = f1.depth_m[i1] > 0;
  const bool stereo2 = f2.depth_m[i2] > 0;
  const double cos_stereo1 = stereo1 ? std::cos(2 * std::atan2(cam1.baseline_m() / 2, f1.depth_m[i1])) : 2.0;
  const double cos_stereo2 = stereo2 ? std::cos(2 * std::atan2(cam2.baseline_m() / 2, f2.depth_m[i2])) : 2.0;
  const double cos_stereo = std::min(cos_stereo1, cos_stereo2);

  if (cos_rays < cos_stereo && cos_rays > 0 && (stereo1 || stereo2 || cos_rays < 0.9998)) {
    return geometry::triangulate_normalized(v1.cam_from_world, n1, v2.cam_from_world, n2);
  }
  if (stereo1 && cos_stereo1 < cos_stereo2) {
    return v1.cam_from_world.inverse() * cam1.unproject(px1, f1.depth_m[i1]);
  }
  if (stereo2 && cos_stereo2 < cos_stereo1) {
    return v2.cam_from_world.inverse() * cam2.unproject(px2, f2.depth_m[i2]);
  }
  return std::nullopt;  // low parallax and no depth
}

bool passes_checks(const View& v1, size_t i1, const View& v2, size_t i2, const geometry::Vec3& world) {
  const auto& f1 = *v1.keyframe.features;
  const auto& f2 = *v2.keyframe.features;
  const auto& levels = *v1.keyframe.levels;
  if (!geometry::has_positive_depth(v1.cam_from_world, world) || !geometry::has_positive_depth(v2.cam_from_world, world)) {
    return false;
  }
  const int level1 = f1.keys_un[i1].octave;
  const int level2 = f2.keys_un[i2].octave;
  if (!geometry::reprojection_within_threshold(*v1.keyframe.camera, v1.cam_from_world, world, pixel_of(v1.keyframe, i1),
                                               levels.sigma2[level1], f1.right_u[i1])) {
    return false;
  }
  if (!geometry::reprojection_within_threshold(*v2.keyframe.camera, v2.cam_from_world, world, pixel_of(v2.keyframe, i2),
                                               levels.sigma2[level2], f2.right_u[i2])) {
    return false;
  }
  // Scale consistency: distance ratio must agree with the pyramid-level ratio.
  const double dist1 = (world - v1.centre).norm();
  const double dist2 = (world - v2.centre).norm();
  if (dist1 <= 0 || dist2 <= 0) return false;
  const double ratio_dist = dist2 / dist1;
  const double ratio_octave = levels.scale[level1] / levels.scale[level2];
  const double factor = 1.5 * levels.scale_factor;
  return !(ratio_dist * factor < ratio_octave || ratio_dist > ratio_octave * factor);
}

}  // namespace

void LocalMapper::create_new_points(const std::shared_ptr<map::KeyFrame>& keyframe) {
  const size_t n_neighbours = options_.monocular ? 20 : static_cast<size_t>(options_.triangulation_neighbours);
  const View v1{*keyframe, keyframe->cam_from_world(), keyframe->camera_center()};
  int created = 0;
  size_t processed = 0;
  for (const auto& neighbour : keyframe->best_covisible(n_neighbours)) {
    if (processed++ > 0 && has_new_keyframes()) break;
    if (neighbour->is_bad()) continue;
    const View v2{*neighbour, neighbour->cam_from_world(), neighbour->camera_center()};
    const double baseline = (v2.centre - v1.centre).norm();
    if (!options_.monocular) {
      if (baseline < keyframe->camera->baseline_m()) continue;
    } else {
      const float median_depth = neighbour->scene_median_depth();
      if (median_depth <= 0 || baseline / median_depth < 0.01) continue;
    }
    const auto f21 = match::fundamental_between(*keyframe, *neighbour);
    const auto matches = match::search_for_triangulation(*keyframe, *neighbour, f21, false, true);
    for (const auto& [i1, i2] : matches) {
      const auto world = triangulate_match(v1, i1, v2, i2);
      if (!world || !world->allFinite() || !passes_checks(v1, i1, v2, i2, *world)) continue;
      auto point = std::make_shared<map::MapPoint>(map_->next_map_point_id(), *world, keyframe, keyframe->frame_id);
      point->add_observation(keyframe, i1);
      point->add_observation(neighbour, i2);
      keyframe->add_map_point(i1, point);
      neighbour->add_map_point(i2, point);
      point->compute_distinctive_descriptor();
      point->update_normal_and_depth();
      map_->add_map_point(point);
      recent_points_.push_back(point);
      ++created;
    }
  }
  std::lock_guard lock(stats_mutex_);
  stats_.points_created += created;
}

}  // namespace crowdslam::mapping
