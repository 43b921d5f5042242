// Keypoints inside person boxes, taken back by the static map (Tracker::track, TrackerOptions::box_keypoints).
//
// The people filter removes every keypoint in a person box before tracking. That is right for a person,
// but a box also hides whatever static background it covers, and a false positive (a poster, a textured
// wall) may cover most of the image: the filtered frame then tracks on a strip, or not at all. Here the
// box keypoints are matched to the local map's trusted points only (seen from several keyframes, never or
// once judged moving by the dynamic check), so a match says "this keypoint looks like the static point
// that projects here". When the filtered frame tracked, a match is kept only if it agrees with that pose
// (the pose optimisation's 95 % chi-square threshold); a person in front of the point does not look like it,
// and one who moves does not agree. When the filtered frame failed, the motion model's pose is the guess
// and the pose optimisation's chi-square classification decides. Nothing new in the map is made of the
// keypoints in boxes (Frame::in_box; Tracker::create_new_keyframe and update_last_frame leave them out).
#include <unordered_map>
#include <unordered_set>

#include "crowdslam/map/map_point.h"
#include "crowdslam/match/orb_matcher.h"
#include "crowdslam/tracking/pose_refinement.h"
#include "crowdslam/tracking/tracker.h"

namespace crowdslam::tracking {

namespace {

// A box whose keypoints are static by the map's account: most of them that match a map point agree with
// the pose (at least 70 % of the matches, 20 or more, and 5 % of the box's keypoints) is not a moving
// person (a false positive on a wall, a person who hides nothing but background in their box). Its
// keypoints are released (no longer in_box), so they become map points like any other; if the box did
// hold a person who moves later, the dynamic check culls what was made of them. Returns how many boxes.
int release_static_boxes(map::Frame& frame, const std::vector<int>& box_of, const std::vector<bool>& disagrees) {
  struct Count {
    int keypoints = 0, matched = 0, inliers = 0;
  };
  std::unordered_map<int, Count> counts;
  for (size_t i = 0; i < frame.size(); ++i) {
    if (!frame.in_box[i] || box_of[i] < 0) continue;
    Count& c = counts[box_of[i]];
    ++c.keypoints;
    if (disagrees[i]) ++c.matched;
    const auto& p = frame.map_points[i];
    if (!p || p->num_observations() < 1) continue;
    ++c.matched;
    if (!frame.outliers[i] && !frame.dynamic[i]) ++c.inliers;
  }
  int released = 0;
  for (const auto& [box, c] : counts) {
    if (c.inliers < 20 || c.inliers < 0.7 * c.matched || c.inliers < 0.05 * c.keypoints) continue;
    ++released;
    for (size_t i = 0; i < frame.size(); ++i) {
      if (box_of[i] == box) frame.in_box[i] = false;
    }
  }
  return released;
}

}  // namespace

std::optional<map::Frame> Tracker::with_box_keypoints(const map::Frame& frame, bool tracked,
                                                      const BoxKeypoints& boxes, int& static_boxes) {
  if (!tracked && !(velocity_ && last_frame_ && last_frame_->cam_from_world)) return std::nullopt;

  if (local_points_.empty()) return std::nullopt;
  auto features = boxes.features();
  if (!features || features->size() != boxes.filtered_index.size()) return std::nullopt;

  map::Frame full(frame.id, frame.timestamp_s, frame.camera, frame.levels, features);
  full.reference_keyframe = frame.reference_keyframe;
  std::vector<bool> had_match(full.size(), false);
  for (size_t i = 0; i < full.size(); ++i) {
    const long k = boxes.filtered_index[i];
    if (k < 0) {
      full.in_box[i] = true;
      continue;
    }
    if (!tracked) continue;
    const auto u = static_cast<size_t>(k);
    full.dynamic[i] = frame.dynamic[u];
    full.motion_history[i] = frame.motion_history[u];
    if (frame.map_points[u] && !frame.outliers[u]) {
      full.map_points[i] = frame.map_points[u];
      had_match[i] = true;
    }
  }
  full.cam_from_world = tracked ? *frame.cam_from_world : *velocity_ * *last_frame_->cam_from_world;
  const int before = tracked ? count_tracked_in_map(full) : 0;

  // The trusted points of the local map that are not matched yet, projected with the pose.
  std::unordered_set<const map::MapPoint*> already;
  for (const auto& p : full.map_points) {
    if (p) already.insert(p.get());
  }
  std::vector<match::ProjectedPoint> projected;
  for (const auto& p : local_points_) {
    if (!p || p->is_bad() || already.count(p.get())) continue;
    if (p->num_observations() < options_.box_min_observations || p->motion_score() > 1) continue;
    if (auto projection = full.project(*p, 0.5)) projected.push_back({p, *projection});
  }
  if (projected.empty()) return std::nullopt;
  match::search_local_points(full, projected, options_.local_map_radius_factor);

  int new_in_box = 0;
  std::vector<bool> disagrees(full.size(), false);
  for (size_t i = 0; i < full.size(); ++i) {
    const auto& p = full.map_points[i];
    if (!p || had_match[i]) continue;
    if (tracked) {
      const MatchResidual r = match_residual(full, i, *p, *full.cam_from_world);
      if (r.chi2 > r.threshold) {
        full.map_points[i].reset();  // disagrees with the pose of the keypoints outside the boxes
        disagrees[i] = true;
        continue;
      }
    }
    if (full.in_box[i]) ++new_in_box;
  }
  if (new_in_box == 0) return std::nullopt;

  optimize_pose(full);
  const int after = count_tracked_in_map(full);
  // Tracked: the box keypoints must add to what the filtered frame had; failed: as many inliers as a
  // pose from a new set of matches needs (ORB-SLAM's 50 after relocalisation).
  if (tracked ? after <= before : after < options_.box_rescue_min_inliers) return std::nullopt;
  for (size_t i = 0; i < full.size(); ++i) {
    const auto& p = full.map_points[i];
    if (p && !had_match[i] && !full.outliers[i]) p->increase_found();
  }
  inliers_in_local_map_ = after;
  static_boxes = release_static_boxes(full, boxes.box_of, disagrees);
  if (!tracked) update_local_map(full);
  full.reference_keyframe = reference_keyframe_;
  return full;
}

std::optional<map::Frame> Tracker::relocalize_with_box_keypoints(const map::Frame& frame, const BoxKeypoints& boxes) {
  auto features = boxes.features();
  if (!features || features->size() != boxes.filtered_index.size()) return std::nullopt;
  map::Frame full(frame.id, frame.timestamp_s, frame.camera, frame.levels, features);
  for (size_t i = 0; i < full.size(); ++i) full.in_box[i] = boxes.filtered_index[i] < 0;
  // Place recognition and the PnP check of relocalize(), then the local map with the 50 inliers asked
  // of a frame right after relocalisation: a box keypoint counts only as a match that agrees.
  if (!relocalize(full)) return std::nullopt;
  full.reference_keyframe = reference_keyframe_;
  if (!track_local_map(full)) return std::nullopt;
  return full;
}

}  // namespace crowdslam::tracking
