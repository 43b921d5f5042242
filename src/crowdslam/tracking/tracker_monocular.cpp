// The monocular parts of the tracker: two-view initialisation and ORB-SLAM2's monocular keyframe policy.
// Everything else (motion model, reference keyframe, local map, relocalisation) is shared with RGB-D: a
// monocular frame simply has no depth, so no visual-odometry or keyframe points are made from depth and
// map points come only from triangulation (two-view initialisation, then the local mapper).
#include <spdlog/spdlog.h>

#include <algorithm>

#include "crowdslam/map/map_point.h"
#include "crowdslam/tracking/frame_bow.h"
#include "crowdslam/tracking/localize_frames.h"
#include "crowdslam/tracking/tracker.h"

namespace crowdslam::tracking {

bool Tracker::initialize_monocular(map::Frame& frame) {
  // Either frame may become one of the two first keyframes, which need their bag of words (keyframe
  // database, loop closing): computed before the initializer keeps a copy of the frame.
  if (vocabulary_) ensure_bow(frame, *vocabulary_);
  const auto init = monocular_initializer_.add_frame(frame);
  const auto remember = [&] { keep_last_frames(frames_before_init_, frame, kMaxFramesBeforeInit); };
  if (!init) {
    remember();
    return false;
  }
  const auto keyframes = build_initial_map(*map_, *init, frame, options_.monocular_init);
  if (!keyframes) {
    // Not enough of the reconstruction survived: start again from this frame.
    monocular_initializer_.reset();
    monocular_initializer_.add_frame(frame);
    frame.cam_from_world.reset();
    std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
    remember();
    return false;
  }
  const auto& [first, second] = *keyframes;
  // The earlier frames are localised before the mapper takes the two keyframes: in the map as sequential
  // mode has it, not in whatever part of it a running mapper has changed.
  recovered_before_init_ = localize_frames_before_init(frame, init->reference->id);
  track_from_two_views(first, second, frame, map_->map_points());
  frames_before_init_.clear();
  monocular_initializer_.reset();
  return true;
}

void Tracker::track_from_two_views(const std::shared_ptr<map::KeyFrame>& first,
                                   const std::shared_ptr<map::KeyFrame>& second, map::Frame& frame,
                                   std::vector<std::shared_ptr<map::MapPoint>> points) {
  mapper_->insert_keyframes(first, second);
  // An unpaced replay tracks the next frame once the mapper has mapped both (as after any keyframe).
  if (options_.monocular_replay_waits && options_.max_wait_for_mapping_ms > 0) next_frame_wait_ = NextFrameWait::kMapped;
  last_keyframe_ = second;
  last_keyframe_frame_id_ = frame.id;
  last_keyframe_indices_.clear();
  reference_keyframe_ = second;
  frame.reference_keyframe = second;
  local_keyframes_ = {first, second};
  local_points_ = std::move(points);
  inliers_in_local_map_ = static_cast<int>(local_points_.size());
  velocity_.reset();  // the next frame is tracked against the reference keyframe
}

std::vector<std::pair<uint64_t, geometry::SE3>> Tracker::localize_frames_before_init(
    const map::Frame& init_frame, uint64_t reference_id) {
  // The frames the initializer saw before the frame that initialised: those after its reference frame
  // lie between the two keyframes (first pose guess: interpolated by time), those before the reference
  // are taken backwards from it (guess: the pose of the frame after, moved by the velocity between the
  // two frames after). Frames between the keyframes that fail are left lost; going backwards stops at
  // the first failure, and the frames left are tried again when the map has grown (retry; the last
  // retry skips over failures).
  frames_to_retry_.clear();
  retries_before_init_ = 0;
  if (frames_before_init_.empty() || !init_frame.cam_from_world) return {};
  const auto reference_kf = map_->keyframes().front();  // sorted by id: the reference frame's keyframe
  auto around = localize_around_two_views(std::move(frames_before_init_), reference_id, reference_kf->cam_from_world(),
                                          reference_kf->timestamp_s, *init_frame.cam_from_world,
                                          init_frame.timestamp_s, map_->map_points(), options_.pose);
  frames_to_retry_ = std::move(around.left);
  retry_step_ = around.step;
  retry_anchor_from_first_ = around.later * reference_kf->world_from_cam();
  retry_first_keyframe_ = reference_kf;
  if (!around.recovered.empty()) {
    spdlog::info("monocular initialisation: {} earlier frames localised in the new map", around.recovered.size());
  }
  return std::move(around.recovered);
}

namespace {
// Frames before the initialisation are tried again when the map has this many keyframes (the two-view
// map's keyframes are the first two).
constexpr size_t kRetryKeyframes[] = {4, 8};
}  // namespace

bool Tracker::retry_before_init_due() const {
  return !frames_to_retry_.empty() && retries_before_init_ < std::size(kRetryKeyframes) &&
         map_->num_keyframes() >= kRetryKeyframes[retries_before_init_];
}

std::vector<std::pair<uint64_t, geometry::SE3>> Tracker::retry_frames_before_init() {
  std::vector<std::pair<uint64_t, geometry::SE3>> recovered;
  if (!retry_before_init_due()) return recovered;
  ++retries_before_init_;
  // The first keyframe (the initializer's reference frame) may have moved in bundle adjustment: the frame
  // after the failed ones is placed relative to it.
  const auto first = retry_first_keyframe_;
  if (!first || first->is_bad()) {
    frames_to_retry_.clear();
    return recovered;
  }
  geometry::SE3 later = retry_anchor_from_first_ * first->cam_from_world();
  // The last retry skips frames that fail (people hiding the view for a moment) as long as it finds one
  // again within kLocalizeMaxGapS: the frames are not tried again after it.
  const bool last_retry = retries_before_init_ >= std::size(kRetryKeyframes);
  recovered = localize_backwards(frames_to_retry_, later, retry_step_, map_->map_points(), options_.pose,
                                 last_retry ? kLocalizeMaxGapS : 0.0);
  retry_anchor_from_first_ = later * first->world_from_cam();
  if (last_retry) frames_to_retry_.clear();
  if (frames_to_retry_.empty()) retry_first_keyframe_.reset();
  std::sort(recovered.begin(), recovered.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  if (!recovered.empty()) {
    spdlog::info("{} frames before the initialisation localised in the map of {} keyframes", recovered.size(),
                 map_->num_keyframes());
  }
  return recovered;
}

Tracker::KeyframeDecision Tracker::need_new_keyframe_monocular(const map::Frame& frame) const {
  // ORB-SLAM2, monocular: a keyframe when the frame tracks less than 90 % of the reference keyframe's
  // points (40 % while the map has one keyframe) and either enough frames have passed or the mapper is
  // idle. No "close points" condition (there is no depth) and no insertion while the mapper is busy:
  // then its bundle adjustment is interrupted so that it becomes free sooner. Unlike ORB-SLAM2, tracking
  // waits for the busy mapper (backpressure) instead of going on without the keyframe: for every due
  // keyframe in an unpaced replay (monocular_replay_waits), otherwise when the keyframe is
  // overdue (max_frames passed), the frame tracks less than half the reference's points, or it tracks
  // few points at all (weak tracking: a keyframe then even when its reference is as weak).
  constexpr double kReferenceRatio = 0.9;
  constexpr double kUrgentRatio = 0.5;
  if (mapper_->is_paused()) return KeyframeDecision::kNo;
  const size_t num_keyframes = map_->num_keyframes();
  const auto max_frames = static_cast<uint64_t>(options_.max_frames_between_keyframes);
  if (last_relocalization_frame_id_ > 0 && frame.id < last_relocalization_frame_id_ + max_frames &&
      num_keyframes > max_frames) {
    return KeyframeDecision::kNo;
  }
  // Points seen by 3 keyframes, as ORB-SLAM2, except while the reference is one of the map's first two
  // keyframes or of the two a re-anchoring placed: their points have two observations, and counting only
  // 3 would hold back keyframes until tracking is weak while the camera moves on into the view they
  // started (this lost re-anchored crowds again within a second).
  const bool two_view_reference = reference_keyframe_ && reference_keyframe_->id >= reanchor_keyframe_ids_.first &&
                                  reference_keyframe_->id <= reanchor_keyframe_ids_.second;
  const int min_observations = num_keyframes <= 2 || two_view_reference ? 2 : 3;
  const int reference_matches =
      reference_keyframe_ ? reference_keyframe_->tracked_map_points(min_observations) : 0;
  const bool mapper_idle = mapper_->accepts_keyframes();
  const double ratio = num_keyframes < 2 ? 0.4 : kReferenceRatio;
  const bool c1a = frame.id >= last_keyframe_frame_id_ + max_frames;
  const bool c1b =
      frame.id >= last_keyframe_frame_id_ + static_cast<uint64_t>(options_.min_frames_between_keyframes) &&
      mapper_idle;
  // Weak tracking: the reference keyframe may itself hold few points (a turn, a low frame rate), and then
  // frames that track about as many never fall below the ratio while tracking thins out to nothing.
  const bool weak = inliers_in_local_map_ < options_.monocular_weak_tracking_inliers;
  const bool c2 = (inliers_in_local_map_ < reference_matches * ratio || weak) && inliers_in_local_map_ > 15;
  if (!c2) return KeyframeDecision::kNo;
  if (mapper_idle && (c1a || c1b)) return KeyframeDecision::kInsert;
  mapper_->interrupt_bundle_adjustment();
  const bool urgent = options_.monocular_replay_waits || c1a || weak ||
                      inliers_in_local_map_ < reference_matches * kUrgentRatio;
  return urgent && options_.max_wait_for_mapping_ms > 0 ? KeyframeDecision::kWaitForMapper
                                                        : KeyframeDecision::kNo;
}

}  // namespace crowdslam::tracking
