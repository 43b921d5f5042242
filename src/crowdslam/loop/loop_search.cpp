#include "crowdslam/loop/loop_search.h"

#include <optional>
#include <unordered_set>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/match/orb_matcher.h"

namespace crowdslam::loop {
namespace {

struct Projection {
  geometry::Vec2 pixel;
  int level = 0;
  double radius_px = 0;
};

// Where `world` falls in `keyframe` seen from cam_from_world (rigid; a Sim3 pose is converted by the
// caller), with ORB-SLAM's frustum checks: in front, inside the image, within the point's scale-invariance
// range and (if check_normal) at a viewing angle below 60 degrees.
std::optional<Projection> project(const map::KeyFrame& keyframe, const geometry::SE3& cam_from_world,
                                  const geometry::Vec3& world, const map::MapPoint& point, double radius,
                                  bool check_normal) {
  const geometry::Vec3 in_cam = cam_from_world * world;
  if (in_cam.z() <= 0) return std::nullopt;
  const geometry::Vec2 pixel = keyframe.camera->project(in_cam);
  if (!keyframe.features->grid.bounds().contains(pixel)) return std::nullopt;
  const double distance = in_cam.norm();
  if (distance < point.min_distance() || distance > point.max_distance()) return std::nullopt;
  if (check_normal) {
    const geometry::Vec3 centre = cam_from_world.inverse().translation();
    if ((world - centre).dot(point.normal()) < 0.5 * distance) return std::nullopt;
  }
  const int level = point.predict_scale(static_cast<float>(distance), *keyframe.levels);
  return Projection{pixel, level, radius * keyframe.levels->scale[level]};
}

// Best keypoint of `keyframe` for `descriptor` around the projection; levels in [min_level, max_level].
// Returns {index, distance} (index -1 when none).
std::pair<int, int> best_in_window(const map::KeyFrame& keyframe, const Projection& proj, const uint8_t* descriptor,
                                   int min_level, int max_level,
                                   const std::vector<std::shared_ptr<map::MapPoint>>* skip_set_slots) {
  const map::FrameFeatures& f = *keyframe.features;
  const auto candidates = f.grid.features_in_area(f.keys_un, static_cast<float>(proj.pixel.x()),
                                                  static_cast<float>(proj.pixel.y()),
                                                  static_cast<float>(proj.radius_px));
  int best_distance = 256;
  int best_index = -1;
  for (size_t idx : candidates) {
    if (skip_set_slots && (*skip_set_slots)[idx]) continue;
    const int octave = f.keys_un[idx].octave;
    if (octave < min_level || octave > max_level) continue;
    const int d = feature::hamming_distance(descriptor, f.descriptor(idx));
    if (d < best_distance) {
      best_distance = d;
      best_index = static_cast<int>(idx);
    }
  }
  return {best_index, best_distance};
}

}  // namespace

int search_by_sim3(const map::KeyFrame& kf1, const map::KeyFrame& kf2,
                   std::vector<std::shared_ptr<map::MapPoint>>& matches_12, const geometry::Sim3& cam1_from_cam2,
                   double radius) {
  const geometry::SE3 cam1_from_world = kf1.cam_from_world();
  const geometry::SE3 cam2_from_world = kf2.cam_from_world();
  const geometry::Sim3 cam2_from_cam1 = cam1_from_cam2.inverse();
  const auto points1 = kf1.map_points();
  const auto points2 = kf2.map_points();
  matches_12.resize(points1.size());

  // kf2 points already matched are not searched again.
  std::unordered_set<uint64_t> already_matched;
  for (const auto& p : matches_12) {
    if (p) already_matched.insert(p->id);
  }

  // Maps a point of one keyframe into the other through the similarity and searches there. The rigid
  // pose used for the checks is identity (coordinates are already in the target camera).
  auto search = [&](const map::KeyFrame& target, const geometry::Vec3& in_target, const map::MapPoint& point,
                    const uint8_t* descriptor) -> int {
    // in_target are camera coordinates: express it as a "world" seen from an identity pose.
    const auto proj = project(target, geometry::SE3(), in_target, point, radius, false);
    if (!proj) return -1;
    const auto [index, distance] =
        best_in_window(target, *proj, descriptor, proj->level - 1, proj->level + 1, nullptr);
    return distance <= match::kThHigh ? index : -1;
  };

  // kf1 -> kf2
  std::vector<int> match_1_to_2(points1.size(), -1);
  for (size_t i = 0; i < points1.size(); ++i) {
    const auto& p = points1[i];
    if (!p || p->is_bad() || matches_12[i]) continue;
    const geometry::Vec3 in_cam2 = cam2_from_cam1 * (cam1_from_world * p->world());
    const map::Descriptor d = p->descriptor();
    match_1_to_2[i] = search(kf2, in_cam2, *p, d.data());
  }
  // kf2 -> kf1
  std::vector<int> match_2_to_1(points2.size(), -1);
  for (size_t j = 0; j < points2.size(); ++j) {
    const auto& p = points2[j];
    if (!p || p->is_bad() || already_matched.count(p->id)) continue;
    const geometry::Vec3 in_cam1 = cam1_from_cam2 * (cam2_from_world * p->world());
    const map::Descriptor d = p->descriptor();
    match_2_to_1[j] = search(kf1, in_cam1, *p, d.data());
  }
  int found = 0;
  for (size_t i = 0; i < points1.size(); ++i) {
    const int j = match_1_to_2[i];
    if (j < 0 || match_2_to_1[static_cast<size_t>(j)] != static_cast<int>(i)) continue;
    const auto& p2 = points2[static_cast<size_t>(j)];
    if (!p2 || p2->is_bad()) continue;
    matches_12[i] = p2;
    ++found;
  }
  return found;
}

int search_by_projection(const map::KeyFrame& keyframe, const geometry::Sim3& cam_from_world,
                         const std::vector<std::shared_ptr<map::MapPoint>>& points,
                         std::vector<std::shared_ptr<map::MapPoint>>& matched, double radius) {
  const geometry::SE3 pose = cam_from_world.to_se3();
  matched.resize(keyframe.features->size());
  std::unordered_set<uint64_t> already;
  for (const auto& p : matched) {
    if (p) already.insert(p->id);
  }
  int found = 0;
  for (const auto& point : points) {
    if (!point || point->is_bad() || already.count(point->id)) continue;
    const auto proj = project(keyframe, pose, point->world(), *point, radius, true);
    if (!proj) continue;
    const map::Descriptor d = point->descriptor();
    const auto [index, distance] = best_in_window(keyframe, *proj, d.data(), proj->level - 1, proj->level, &matched);
    if (index < 0 || distance > match::kThLow) continue;
    matched[static_cast<size_t>(index)] = point;
    already.insert(point->id);
    ++found;
  }
  return found;
}

int fuse_by_projection(const std::shared_ptr<map::KeyFrame>& keyframe, const geometry::Sim3& cam_from_world,
                       const std::vector<std::shared_ptr<map::MapPoint>>& points, double radius,
                       std::vector<std::shared_ptr<map::MapPoint>>& replace) {
  const geometry::SE3 pose = cam_from_world.to_se3();
  replace.assign(points.size(), nullptr);
  int fused = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    const auto& point = points[k];
    if (!point || point->is_bad() || point->is_observed_by(keyframe->id)) continue;
    const auto proj = project(*keyframe, pose, point->world(), *point, radius, true);
    if (!proj) continue;
    const map::Descriptor d = point->descriptor();
    const auto [index, distance] = best_in_window(*keyframe, *proj, d.data(), proj->level - 1, proj->level, nullptr);
    if (index < 0 || distance > match::kThLow) continue;
    const size_t idx = static_cast<size_t>(index);
    if (auto existing = keyframe->map_point(idx)) {
      if (!existing->is_bad() && existing != point) replace[k] = existing;
    } else {
      point->add_observation(keyframe, idx);
      keyframe->add_map_point(idx, point);
    }
    ++fused;
  }
  return fused;
}

}  // namespace crowdslam::loop
