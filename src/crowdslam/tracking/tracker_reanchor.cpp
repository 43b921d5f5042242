// Monocular re-anchoring (TrackerOptions::reanchor_max_s, docs/CROWDS.md#monocular-re-anchoring): a
// monocular camera lost where its map holds nothing it can see (people hid the map while the camera
// turned to new walls) starts a two-view reconstruction there, as at the start, and places it in the same
// map by the motion tracked before the loss instead of starting a new map.
#include <spdlog/spdlog.h>

#include <algorithm>

#include "crowdslam/map/map_point.h"
#include "crowdslam/tracking/frame_bow.h"
#include "crowdslam/tracking/localize_frames.h"
#include "crowdslam/tracking/tracker.h"

namespace crowdslam::tracking {

namespace {
constexpr double kReanchorPriorS = 1.0;
}  // namespace

MonocularInitializerOptions reanchor_initializer_options(MonocularInitializerOptions options) {
  // What people leave of a view is a few hundred keypoints: all pyramid levels up to 2 take part, and
  // fewer matches and points do (the placement, not the two views alone, fixes the pose).
  options.max_level = std::max(options.max_level, 2);
  options.min_matches = std::min(options.min_matches, 70);
  options.min_map_points = std::min(options.min_map_points, 70);
  return options;
}

void Tracker::start_reanchor(const std::optional<BridgeMotion>& motion, double lost_since_s) {
  reanchor_.reset();
  reanchor_initializer_.reset();
  reanchor_initializer_.clear_prior();
  frames_since_loss_.clear();
  if (options_.reanchor_max_s <= 0 || !motion || map_loaded_ || localization_only_) return;
  if (map_->num_keyframes() <= static_cast<size_t>(options_.reset_if_lost_within_keyframes)) return;
  const auto reference = reference_keyframe_ && !reference_keyframe_->is_bad() ? reference_keyframe_ : last_keyframe_;
  const float depth = reference ? reference->scene_median_depth() : 0.0F;
  if (!(depth > 0)) return;
  reanchor_ = Reanchor{*motion, lost_since_s, depth, reference};
  // The two views must agree with the motion tracked before the loss: where the people left a plane (a
  // wall) its two decompositions both explain every match, and only the motion tells them apart. The
  // motion is trusted for kReanchorPriorS after the last pose: later (a long blackout) the camera may have
  // changed its motion, and the two views decide alone, as at the start.
  reanchor_initializer_.set_prior([motion = *motion, depth](double reference_s, double current_s) {
    if (current_s - motion.anchor_s > kReanchorPriorS) return std::optional<geometry::TwoViewPrior>();
    geometry::TwoViewPrior prior;
    prior.cam2_from_cam1 = motion.at(current_s) * motion.at(reference_s).inverse();
    // A travel under 1 % of the scene depth has no direction to speak of (the views' parallax is below
    // what an initialisation needs anyway).
    prior.check_direction = prior.cam2_from_cam1.translation().norm() >= 0.01 * depth;
    return std::optional<geometry::TwoViewPrior>(prior);
  });
}

bool Tracker::reanchor_while_bridged(map::Frame& frame, const std::optional<BridgeMotion>& motion,
                                     TrackResult& result) {
  if (!options_.monocular || options_.reanchor_max_s <= 0 || map_loaded_ || localization_only_ || !motion ||
      !frame.cam_from_world) {
    return false;
  }
  size_t background = 0;
  for (size_t i = 0; i < frame.size(); ++i) background += !frame.in_box[i] && !frame.dynamic[i];
  if (options_.bridge_resume_min_keypoints <= 0 ||
      background < static_cast<size_t>(options_.bridge_resume_min_keypoints) ||
      map_points_near_keypoints(frame) >= static_cast<size_t>(options_.bridge_resume_max_map_points)) {
    return false;  // people hide the view, or the map holds it (relocalisation will find it)
  }
  if (!reanchor_) start_reanchor(motion, frame.timestamp_s);
  if (!reanchor_) return false;
  const geometry::SE3 bridged = *frame.cam_from_world;
  if (reanchor(frame, result)) return true;
  frame.cam_from_world = bridged;  // still bridged
  return false;
}

bool Tracker::reanchor(map::Frame& frame, TrackResult& result) {
  // Counted from the loss, like the new-map clock: after a bridge, from when the view cleared.
  if (frame.timestamp_s - reanchor_->lost_since_s > options_.reanchor_max_s) {
    spdlog::info("monocular re-anchoring given up {:.1f} s after tracking was lost", options_.reanchor_max_s);
    reanchor_.reset();
    reanchor_initializer_.reset();
    frames_since_loss_.clear();
    return false;
  }
  if (vocabulary_) ensure_bow(frame, *vocabulary_);  // either frame may become a keyframe
  const auto init = reanchor_initializer_.add_frame(frame);
  // The lost frames are kept, to be localised in the map once it is re-anchored.
  const auto keep = [&] { keep_last_frames(frames_since_loss_, frame, kMaxFramesBeforeInit); };
  if (!init) {
    keep();
    return false;
  }
  const BridgeMotion& motion = reanchor_->motion;
  InitialMapPlacement placement;
  placement.reference_cam_from_world = motion.at(init->reference->timestamp_s);
  const geometry::SE3 current_pose = motion.at(frame.timestamp_s);
  placement.predicted_baseline =
      (current_pose.inverse().translation() - placement.reference_cam_from_world.inverse().translation()).norm();
  placement.expected_median_depth = reanchor_->median_depth;
  placement.parent = reanchor_->keyframe;
  if (!placement.parent || placement.parent->is_bad()) {
    const auto keyframes = map_->keyframes();
    for (auto it = keyframes.rbegin(); it != keyframes.rend(); ++it) {
      if (!(*it)->is_bad()) {
        placement.parent = *it;
        break;
      }
    }
  }
  const auto keyframes = build_initial_map(*map_, *init, frame, options_.monocular_init, &placement);
  if (!keyframes) {
    reanchor_initializer_.reset();
    reanchor_initializer_.add_frame(frame);
    frame.cam_from_world.reset();
    std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
    keep();
    return false;
  }
  const auto& [first, second] = *keyframes;
  spdlog::info(
      "monocular re-anchoring: frames {} and {} placed in the map {:.2f} s after the last pose, scale {:.3f} "
      "from the {} ({} points)",
      init->reference->id, frame.id, frame.timestamp_s - motion.anchor_s, placement.scale,
      placement.scaled_by_baseline ? "predicted baseline" : "scene depth", second->tracked_map_points(1));
  // The frames lost before: between the two views, and before the first (backwards from it, skipping
  // those that fail as long as one is localised again within kLocalizeMaxGapS; they are not tried again).
  // Before the mapper takes the two keyframes, as in sequential mode.
  auto around = localize_around_two_views(
      std::move(frames_since_loss_), first->frame_id, first->cam_from_world(), first->timestamp_s,
      *frame.cam_from_world, frame.timestamp_s, map_->map_points(), options_.pose, kLocalizeMaxGapS);
  frames_since_loss_.clear();
  result.recovered = std::move(around.recovered);
  result.recovered.emplace_back(first->frame_id, first->cam_from_world());
  track_from_two_views(first, second, frame, second->valid_map_points());
  frame.discard_outliers();
  result.recovered_reference = first;
  reanchor_keyframe_ids_ = {std::min(first->id, second->id), std::max(first->id, second->id)};
  if (result.recovered.size() > 1) {
    spdlog::info("monocular re-anchoring: {} lost frames localised in the map", result.recovered.size() - 1);
  }
  reanchor_initializer_.reset();
  reanchor_.reset();
  lost_frames_ = 0;
  last_tracked_s_ = frame.timestamp_s;
  last_bridged_s_.reset();
  return true;
}

}  // namespace crowdslam::tracking
