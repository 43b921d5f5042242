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
// and the pose optimisation's chi-square classification decides. A box the evidence shows static (its
// map matches, or with depth the last frame's box keypoints landing where the pose says) is released and
// mapped; nothing new in the map is made of any other box keypoint (Frame::in_box;
// Tracker::create_new_keyframe and update_last_frame leave them out).
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
// `flow`: per keypoint without a map point, +1 / -1 when its match to the last frame's box keypoints (with
// depth) agrees / disagrees with the pose (box_flow_evidence), 0 = none.
int release_static_boxes(map::Frame& frame, const std::vector<int>& box_of, const std::vector<bool>& disagrees,
                         const std::vector<int8_t>& flow) {
  struct Count {
    int keypoints = 0, matched = 0, inliers = 0, flow_in = 0, flow_out = 0;
  };
  std::unordered_map<int, Count> counts;
  for (size_t i = 0; i < frame.size(); ++i) {
    if (!frame.in_box[i] || box_of[i] < 0) continue;
    Count& c = counts[box_of[i]];
    ++c.keypoints;
    if (disagrees[i]) ++c.matched;
    const auto& p = frame.map_points[i];
    if (!p || p->num_observations() < 1) {
      if (flow[i] > 0) ++c.flow_in;
      if (flow[i] < 0) ++c.flow_out;
      continue;
    }
    ++c.matched;
    if (!frame.outliers[i] && !frame.dynamic[i]) ++c.inliers;
  }
  int released = 0;
  for (const auto& [box, c] : counts) {
    const bool by_map = c.inliers >= 20 && c.inliers >= 0.7 * c.matched && c.inliers >= 0.05 * c.keypoints;
    const bool by_flow = c.flow_in >= 20 && c.flow_in >= 0.85 * (c.flow_in + c.flow_out) && c.flow_in >= 0.25 * c.keypoints;
    if (!by_map && !by_flow) continue;
    ++released;
    for (size_t i = 0; i < frame.size(); ++i) {
      if (box_of[i] == box) frame.in_box[i] = false;
    }
  }
  return released;
}

}  // namespace

std::optional<map::Frame> Tracker::with_box_keypoints(const map::Frame& frame, bool tracked,
                                                      const BoxKeypoints& boxes, int& static_boxes,
                                                      const std::optional<geometry::SE3>& guess) {
  std::optional<geometry::SE3> pose;
  if (tracked) {
    pose = frame.cam_from_world;
  } else if (velocity_ && last_frame_ && last_frame_->cam_from_world) {
    pose = *velocity_ * *last_frame_->cam_from_world;
  } else {
    pose = guess;
  }
  if (!pose) return std::nullopt;
  if (!tracked && !options_.box_rescue) return std::nullopt;

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
  full.cam_from_world = *pose;
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
  if (!projected.empty()) match::search_local_points(full, projected, options_.local_map_radius_factor);

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
  if (new_in_box == 0 && !tracked) return std::nullopt;

  if (new_in_box > 0) optimize_pose(full);
  const int after = count_tracked_in_map(full);
  // Tracked: the box keypoints must not lose what the filtered frame had; failed: as many inliers as a
  // pose from a new set of matches needs (ORB-SLAM's 50 after relocalisation; 30 in monocular).
  if (tracked ? after < before : after < options_.box_rescue_min_inliers) return std::nullopt;
  if (!tracked) {  // the pose from box keypoints near the motion model's (box_rescue_gate_*)
    const PoseGap gap = pose_gap(*full.cam_from_world, *pose);
    if ((options_.box_rescue_gate_m > 0 && gap.metres > options_.box_rescue_gate_m) ||
        (options_.box_rescue_gate_deg > 0 && gap.degrees > options_.box_rescue_gate_deg))
      return std::nullopt;
  }
  std::vector<int8_t> flow(full.size(), 0);
  box_flow_evidence(full, flow);
  static_boxes = options_.box_release ? release_static_boxes(full, boxes.box_of, disagrees, flow) : 0;
  remember_box_frame(full);
  if (new_in_box == 0 && static_boxes == 0) return std::nullopt;  // nothing gained
  for (size_t i = 0; i < full.size(); ++i) {
    const auto& p = full.map_points[i];
    if (p && !had_match[i] && !full.outliers[i]) p->increase_found();
  }
  inliers_in_local_map_ = after;
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

void Tracker::remember_box_frame(const map::Frame& full) {
  if (!full.camera->is_stereo() || !full.cam_from_world) return;  // the evidence needs depth
  last_box_frame_.emplace(full.id, full.timestamp_s, full.camera, full.levels, full.features);
  last_box_frame_->cam_from_world = full.cam_from_world;
  last_box_frame_->in_box = full.in_box;
}

void Tracker::box_flow_evidence(const map::Frame& full, std::vector<int8_t>& flow) const {
  // The last frame's box keypoints with depth, as points in the world (from the last pose), matched into
  // this frame's box keypoints that have no map point: a static surface lands where the pose says, a
  // person who walks does not. Evidence for release only; the pose never uses these matches.
  if (!last_box_frame_ || last_box_frame_->id + 1 != full.id || !full.cam_from_world) return;
  const map::Frame& last = *last_box_frame_;
  const auto& lf = *last.features;
  map::Frame probe(last.id, last.timestamp_s, last.camera, last.levels, last.features);
  probe.cam_from_world = last.cam_from_world;
  int points = 0;
  for (size_t i = 0; i < lf.size(); ++i) {
    if (!last.in_box[i] || lf.depth_m.empty() || lf.depth_m[i] <= 0) continue;
    probe.map_points[i] = point_from_depth(last, i);
    ++points;
  }
  if (points == 0) return;
  map::Frame target(full.id, full.timestamp_s, full.camera, full.levels, full.features);
  target.cam_from_world = full.cam_from_world;
  match::search_from_last_frame(target, probe, options_.motion_model_radius);
  for (size_t i = 0; i < full.size(); ++i) {
    const auto& p = target.map_points[i];
    if (!p || !full.in_box[i] || full.map_points[i]) continue;
    const MatchResidual r = match_residual(target, i, *p, *full.cam_from_world);
    flow[i] = r.chi2 <= r.threshold ? 1 : -1;
  }
}

}  // namespace crowdslam::tracking
