// The monocular parts of the tracker: two-view initialisation and ORB-SLAM2's monocular keyframe policy.
// Everything else (motion model, reference keyframe, local map, relocalisation) is shared with RGB-D: a
// monocular frame simply has no depth, so no visual-odometry or keyframe points are made from depth and
// map points come only from triangulation (two-view initialisation, then the local mapper).
#include <spdlog/spdlog.h>

#include "crowdslam/map/map_point.h"
#include "crowdslam/tracking/frame_bow.h"
#include "crowdslam/tracking/tracker.h"

namespace crowdslam::tracking {

bool Tracker::initialize_monocular(map::Frame& frame) {
  // Either frame may become one of the two first keyframes, which need their bag of words (keyframe
  // database, loop closing): computed before the initializer keeps a copy of the frame.
  if (vocabulary_) ensure_bow(frame, *vocabulary_);
  const auto init = monocular_initializer_.add_frame(frame);
  if (!init) return false;
  const auto keyframes = build_initial_map(*map_, *init, frame, options_.monocular_init);
  if (!keyframes) {
    // Not enough of the reconstruction survived: start again from this frame.
    monocular_initializer_.reset();
    monocular_initializer_.add_frame(frame);
    frame.cam_from_world.reset();
    std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
    return false;
  }
  const auto& [first, second] = *keyframes;
  mapper_->insert_keyframe(first);
  mapper_->insert_keyframe(second);
  last_keyframe_ = second;
  last_keyframe_frame_id_ = frame.id;
  reference_keyframe_ = second;
  frame.reference_keyframe = second;
  local_keyframes_ = {first, second};
  local_points_ = map_->map_points();
  inliers_in_local_map_ = static_cast<int>(local_points_.size());
  velocity_.reset();  // the next frame is tracked against the reference keyframe
  monocular_initializer_.reset();
  return true;
}

Tracker::KeyframeDecision Tracker::need_new_keyframe_monocular(const map::Frame& frame) const {
  // ORB-SLAM2, monocular: a keyframe when the frame tracks less than 90 % of the reference keyframe's
  // points (40 % while the map has one keyframe) and either enough frames have passed or the mapper is
  // idle. No "close points" condition (there is no depth) and no insertion while the mapper is busy:
  // then its bundle adjustment is interrupted so that it becomes free sooner. Unlike ORB-SLAM2, when
  // the keyframe is overdue (max_frames passed) or the frame tracks less than half the reference's
  // points, tracking waits for the mapper (backpressure) instead of running out of map points.
  constexpr double kReferenceRatio = 0.9;
  constexpr double kUrgentRatio = 0.5;
  if (mapper_->is_paused()) return KeyframeDecision::kNo;
  const size_t num_keyframes = map_->num_keyframes();
  const auto max_frames = static_cast<uint64_t>(options_.max_frames_between_keyframes);
  if (last_relocalization_frame_id_ > 0 && frame.id < last_relocalization_frame_id_ + max_frames &&
      num_keyframes > max_frames) {
    return KeyframeDecision::kNo;
  }
  const int min_observations = num_keyframes <= 2 ? 2 : 3;
  const int reference_matches =
      reference_keyframe_ ? reference_keyframe_->tracked_map_points(min_observations) : 0;
  const bool mapper_idle = mapper_->accepts_keyframes();
  const double ratio = num_keyframes < 2 ? 0.4 : kReferenceRatio;
  const bool c1a = frame.id >= last_keyframe_frame_id_ + max_frames;
  const bool c1b =
      frame.id >= last_keyframe_frame_id_ + static_cast<uint64_t>(options_.min_frames_between_keyframes) &&
      mapper_idle;
  const bool c2 = inliers_in_local_map_ < reference_matches * ratio && inliers_in_local_map_ > 15;
  if (!c2) return KeyframeDecision::kNo;
  if (mapper_idle && (c1a || c1b)) return KeyframeDecision::kInsert;
  mapper_->interrupt_bundle_adjustment();
  const bool urgent = c1a || inliers_in_local_map_ < reference_matches * kUrgentRatio;
  return urgent && options_.max_wait_for_mapping_ms > 0 ? KeyframeDecision::kWaitForMapper : KeyframeDecision::kNo;
}

}  // namespace crowdslam::tracking
