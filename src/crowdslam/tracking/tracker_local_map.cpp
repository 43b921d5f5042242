// Tracking a frame against the map: by the motion model (the last frame's points projected from the
// predicted pose), by the reference keyframe (bag of words), and the local map (ORB-SLAM2's TrackLocalMap):
// the keyframes that see the frame's points and their neighbours, their points projected into the frame
// and matched, and the pose refined on all matches.
#include <algorithm>
#include <unordered_map>
#include <unordered_set>

#include "crowdslam/map/map_point.h"
#include "crowdslam/match/bow_search.h"
#include "crowdslam/match/orb_matcher.h"
#include "crowdslam/tracking/frame_bow.h"
#include "crowdslam/tracking/pose_refinement.h"
#include "crowdslam/tracking/tracker.h"

namespace crowdslam::tracking {

bool Tracker::track_with_motion_model(map::Frame& frame) {
  update_last_frame();
  frame.cam_from_world = *velocity_ * *last_frame_->cam_from_world;
  std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
  int matches = match::search_from_last_frame(frame, *last_frame_, options_.motion_model_radius);
  if (matches < 20) {
    std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
    matches = match::search_from_last_frame(frame, *last_frame_, 2 * options_.motion_model_radius);
  }
  if (matches < 20) return false;
  const int inliers = optimize_pose(frame);
  const int in_map = discard_outliers_count_map_points(frame);
  if (in_map < 10 && !options_.monocular && options_.odometry_bridge_min_inliers > 0 &&
      inliers >= options_.odometry_bridge_min_inliers) {
    odometry_bridge_ = frame;
  }
  return in_map >= 10;
}

bool Tracker::track_reference_keyframe(map::Frame& frame) {
  if (!reference_keyframe_ || !last_frame_ || !last_frame_->cam_from_world) return false;
  if (vocabulary_) ensure_bow(frame, *vocabulary_);
  int matches = 0;
  if (frame.features->has_bow() && reference_keyframe_->features->has_bow()) {
    // Bag-of-words guided matching (no pose guess needed).
    matches = match::search_by_bow(*reference_keyframe_, frame, frame.map_points, 0.7, true);
  } else {
    std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
    matches = match::search_keyframe_window(frame, *reference_keyframe_, options_.keyframe_window_radius);
  }
  if (matches < 15) return false;
  frame.cam_from_world = *last_frame_->cam_from_world;
  optimize_pose(frame);
  return discard_outliers_count_map_points(frame) >= 10;
}

void Tracker::update_local_map(const map::Frame& frame) {
  // Keyframes that see the frame's points, weighted by how many.
  std::unordered_map<uint64_t, std::pair<std::shared_ptr<map::KeyFrame>, int>> counter;
  for (const auto& p : frame.map_points) {
    if (!p || p->is_bad()) continue;
    p->for_each_observation([&](uint64_t kf_id, const map::MapPoint::Observation& obs) {
      auto& entry = counter[kf_id];
      if (!entry.first) entry.first = obs.keyframe.lock();
      ++entry.second;
    });
  }
  for (auto it = counter.begin(); it != counter.end();) {  // keyframes already gone
    it = it->second.first ? std::next(it) : counter.erase(it);
  }
  if (counter.empty()) return;
  local_keyframes_.clear();
  std::unordered_set<uint64_t> included;
  std::shared_ptr<map::KeyFrame> best;
  int best_count = 0;
  for (const auto& [id, entry] : counter) {
    if (entry.first->is_bad()) continue;
    if (entry.second > best_count) {
      best_count = entry.second;
      best = entry.first;
    }
    local_keyframes_.push_back(entry.first);
    included.insert(id);
  }
  // Neighbours of those: best covisibles, children and parent (one of each per keyframe).
  const size_t first_ring = local_keyframes_.size();
  auto try_add = [&](const std::shared_ptr<map::KeyFrame>& kf) {
    if (!kf || kf->is_bad() || included.count(kf->id)) return false;
    included.insert(kf->id);
    local_keyframes_.push_back(kf);
    return true;
  };
  for (size_t k = 0; k < first_ring; ++k) {
    if (local_keyframes_.size() > static_cast<size_t>(options_.max_local_keyframes)) break;
    const auto kf = local_keyframes_[k];
    for (const auto& neighbour : kf->best_covisible(10)) {
      if (try_add(neighbour)) break;
    }
    for (const auto& child : kf->children()) {
      if (try_add(child)) break;
    }
    try_add(kf->parent());
  }
  if (best) reference_keyframe_ = best;

  local_points_.clear();
  const uint64_t pass = map::MapPoint::next_mark();
  for (const auto& kf : local_keyframes_) {
    kf->for_each_map_point([&](const std::shared_ptr<map::MapPoint>& p) {
      if (!p->is_bad() && p->mark(pass)) local_points_.push_back(p);
    });
  }
}

bool Tracker::track_local_map(map::Frame& frame) {
  update_local_map(frame);
  frame.reference_keyframe = reference_keyframe_;

  const uint64_t in_frame = map::MapPoint::next_mark();  // the frame's own points are not searched again
  for (const auto& p : frame.map_points) {
    if (!p || p->is_bad()) continue;
    p->mark(in_frame);
    p->increase_visible();
  }
  std::vector<match::ProjectedPoint> projected;
  projected.reserve(local_points_.size());
  for (const auto& p : local_points_) {
    if (p->marked(in_frame)) continue;
    if (auto projection = frame.project(*p, 0.5)) {
      p->increase_visible();
      projected.push_back({p, *projection});
    }
  }
  projected_local_points_ = projected.size();
  if (!projected.empty()) match::search_local_points(frame, projected, options_.local_map_radius_factor);

  optimize_pose(frame);
  int inliers = 0;
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    const auto& p = frame.map_points[i];
    if (!p || frame.outliers[i]) continue;
    p->increase_found();
    if (p->num_observations() > 0) ++inliers;
  }
  inliers_in_local_map_ = inliers;
  const bool recently_relocalized =
      frame.id <
          last_relocalization_frame_id_ + static_cast<uint64_t>(options_.max_frames_between_keyframes) &&
      last_relocalization_frame_id_ > 0;
  if (recently_relocalized && inliers < 50) return false;
  return inliers >= 30;
}

}  // namespace crowdslam::tracking
