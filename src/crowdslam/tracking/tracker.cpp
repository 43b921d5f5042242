#include "crowdslam/tracking/tracker.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <string_view>
#include <unordered_set>

#include "crowdslam/loop/keyframe_database.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/match/bow_search.h"
#include "crowdslam/match/orb_matcher.h"
#include "crowdslam/tracking/frame_bow.h"
#include "crowdslam/tracking/pose_refinement.h"
#include "crowdslam/util/error.h"

namespace crowdslam::tracking {

const char* to_string(TrackingState state) {
  switch (state) {
    case TrackingState::kNotInitialized:
      return "not_initialized";
    case TrackingState::kOk:
      return "ok";
    case TrackingState::kLost:
      return "lost";
    case TrackingState::kBridged:
      return "bridged";
  }
  return "?";
}

void TrackerOptions::check() const {
  if (!(close_depth_m > 0)) throw InputError("tracker: close depth (ThDepth) must be > 0");
  if (min_init_features < 10 || min_init_static_features < 10)
    throw InputError("tracker: min_init_features and min_init_static_features must be >= 10");
  if (!(box_rescue_after_bridge_s >= 0) || !(box_rescue_gate_m >= 0) || !(box_rescue_gate_deg >= 0))
    throw InputError("tracker: box_rescue_after_bridge_s and box_rescue_gate_* must be >= 0");
  if (max_frames_between_keyframes < 1)
    throw InputError("tracker: max frames between keyframes must be >= 1");
  if (keyframe_reference_min_observations < 1)
    throw InputError("tracker: keyframe_reference_min_observations must be >= 1");
  if (keyframe_reference_min_found < 0)
    throw InputError("tracker: keyframe_reference_min_found must be >= 0");
  if (!(bridge_max_s >= 0)) throw InputError("tracker: bridge_max_s must be >= 0");
  if (!(reanchor_max_s >= 0)) throw InputError("tracker: reanchor_max_s must be >= 0");
  if (!(bridge_min_people_share >= 0 && bridge_min_people_share <= 1))
    throw InputError("tracker: bridge_min_people_share must be in [0, 1]");
  if (!(bridge_near_depth_ratio >= 0 && bridge_near_depth_ratio < 1))
    throw InputError("tracker: bridge_near_depth_ratio must be in [0, 1)");
  if (bridge_resume_min_keypoints < 0) throw InputError("tracker: bridge_resume_min_keypoints must be >= 0");
  if (!(bridge_resume_recent_s >= 0)) throw InputError("tracker: bridge_resume_recent_s must be >= 0");
  if (bridge_resume_min_depth_keypoints < 0)
    throw InputError("tracker: bridge_resume_min_depth_keypoints must be >= 0");
  if (!(bridge_gate_base_m >= 0 && bridge_gate_m_per_s >= 0 && bridge_gate_base_deg >= 0 &&
        bridge_gate_deg_per_s >= 0)) {
    throw InputError("tracker: bridge_gate_* must be >= 0");
  }
  pose.check();
  dynamic.check();
  if (monocular) monocular_init.check();
}

Tracker::Tracker(const TrackerOptions& options, std::shared_ptr<map::Map> map, KeyframeConsumer* mapper)
    : options_(options),
      map_(std::move(map)),
      mapper_(mapper),
      monocular_initializer_(options.monocular_init),
      reanchor_initializer_(reanchor_initializer_options(options.monocular_init)),
      dynamic_check_(options.dynamic) {
  options_.check();
}

void Tracker::reset() {
  lost_frames_ = 0;
  last_tracked_s_.reset();
  last_bridged_s_.reset();
  bridged_seen_s_.reset();
  bridge_motion_.reset();
  bridge_recent_motion_.reset();
  reanchor_.reset();
  reanchor_keyframe_ids_ = {1, 0};
  frames_since_loss_.clear();
  recent_poses_.clear();
  scene_depth_m_ = 0;
  next_frame_wait_ = NextFrameWait::kNone;
  state_ = TrackingState::kNotInitialized;
  last_frame_.reset();
  last_box_frame_.reset();
  velocity_.reset();
  last_cam_from_reference_.reset();
  reference_keyframe_.reset();
  last_keyframe_.reset();
  last_keyframe_indices_.clear();
  temporal_points_.clear();
  local_keyframes_.clear();
  local_points_.clear();
  monocular_initializer_.reset();
  frames_before_init_.clear();
  recovered_before_init_.clear();
  frames_to_retry_.clear();
  retry_first_keyframe_.reset();
  retries_before_init_ = 0;
}

void Tracker::start_in_loaded_map(bool localization_only) {
  reset();
  state_ = TrackingState::kLost;
  map_loaded_ = true;
  localization_only_ = localization_only;
}

TrackResult Tracker::track(map::Frame frame, const BoxKeypoints& boxes, double people_share) {
  TrackResult result;
  result.keypoints = static_cast<int>(frame.size());
  result.people_share = people_share;
  if (next_frame_wait_ != NextFrameWait::kNone) {
    // The last frame made a keyframe: this frame is tracked once the mapper has mapped it (its new
    // points and its local BA), as in sequential mode; otherwise it sees only the points of the keyframe
    // before, one step late (in a turn, on motion that is already losing the map), or the new points as
    // they were before BA (docs/MAPPING.md, "Backpressure").
    const auto wait_start = std::chrono::steady_clock::now();
    mapper_->wait_until_accepting(options_.max_wait_for_mapping_ms);
    next_frame_wait_ = NextFrameWait::kNone;
    result.waited_for_mapping_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wait_start).count();
  }
  std::unique_lock map_lock(map_->update_mutex());

  bool resumed = false;  // mapping went on from a bridged pose: tracking continues, the frame is reported bridged
  if (state_ == TrackingState::kNotInitialized) {
    if (options_.monocular ? initialize_monocular(frame) : initialize(frame, people_share)) {
      state_ = TrackingState::kOk;
      result.method = "init";
      result.new_keyframe = true;
      result.recovered = std::move(recovered_before_init_);
      recovered_before_init_.clear();
      result.recovered_reference = map_->keyframes().front();
    }
  } else {
    bool ok = false;
    const bool was_tracking = state_ == TrackingState::kOk && velocity_ && last_frame_;
    // After bridged frames the last frame's pose is the motion model's: no motion model or odometry from it
    // (velocity_ is empty), but the reference keyframe is searched from that pose.
    const bool after_bridge = state_ == TrackingState::kBridged;
    // The motion a bridge follows, fixed when it starts; worked out only when a frame fails (relocalisation
    // may reset velocity_ before that, so it is taken now).
    const std::optional<geometry::SE3> velocity_at_start = velocity_;
    std::optional<BridgeMotion> motion = bridge_motion_;
    auto start_motion = [&] {
      if (!after_bridge) motion = bridge_motion(frame, velocity_at_start);
      return motion;
    };
    if (last_frame_) replace_replaced_points(*last_frame_);
    bool bridged = false;
    odometry_bridge_.reset();
    // The frame as it came, for the second tries below: without the motion model, and without the dynamic
    // check (which must never be the reason tracking fails).
    std::optional<map::Frame> fresh;
    if (was_tracking) fresh = frame;
    bool by_motion_model = false;
    if (state_ == TrackingState::kOk && velocity_ && last_frame_) {
      ok = track_with_motion_model(frame);
      result.method = "motion";
      by_motion_model = ok;
    }
    if (!ok && (state_ == TrackingState::kOk || after_bridge)) {
      ok = track_reference_keyframe(frame);
      result.method = "reference";
    }
    bool in_local_map = false;
    size_t map_points_in_view = 0;  // where the bridge puts the frame
    std::optional<geometry::SE3> bridged_guess;  // and where the keypoints outside boxes refine that to
    if (!ok && after_bridge && bridge(frame, motion)) {
      ok = in_local_map = track_after_bridge(frame, motion, bridged_guess);
      if (ok) result.method = "motion";
      map_points_in_view = projected_local_points_;
    }
    if (!ok) {
      ok = relocalize(frame);
      result.method = "relocalization";
    }
    frame.reference_keyframe = reference_keyframe_;
    if (ok && !in_local_map) ok = track_local_map(frame);
    if (!ok && by_motion_model && fresh) {
      // The motion model found matches but too few of the local map agree with its pose: on a turn that
      // speeds up or slows down, the matches in its search windows can hold a wrong pose. The reference
      // keyframe's bag of words needs no pose guess.
      map::Frame again = *fresh;
      if (track_reference_keyframe(again)) {
        again.reference_keyframe = reference_keyframe_;
        if (track_local_map(again)) {
          frame = std::move(again);
          ok = true;
          result.method = "reference";
        }
      }
    }
    if (!ok && fresh && dynamic_check_.enabled() && velocity_) {
      dynamic_check_.set_suspended(true);
      map::Frame again = std::move(*fresh);
      if (track_with_motion_model(again)) {
        again.reference_keyframe = reference_keyframe_;
        if (track_local_map(again)) {
          frame = std::move(again);
          ok = true;
          result.method = "motion";
          result.dynamic.skipped = true;
        }
      }
      dynamic_check_.set_suspended(false);
    }
    if (ok && after_bridge && motion && !options_.monocular && !agrees_with_bridge(frame, *motion)) {
      // Matched through its bag of words or relocalised far from where the bridge puts it moments after a
      // short occlusion: the matches are on people the detector missed or on look-alike texture.
      spdlog::debug("frame {}: {} pose rejected, too far from the bridged pose", frame.id, result.method);
      ok = false;
    }
    // While bridged, the keypoints in boxes are searched from where the bridge puts the frame: a person
    // close to a monocular camera hides the map outside the boxes, not behind them.
    if (!ok && after_bridge && motion && !bridged_guess) bridged_guess = motion->at(frame.timestamp_s);
    // A frame moments after a bridge is left to the bridge (box_rescue_after_bridge_s).
    const bool rescue_waits = options_.box_rescue_after_bridge_s > 0 && bridged_seen_s_ &&
                              std::abs(frame.timestamp_s - *bridged_seen_s_) < options_.box_rescue_after_bridge_s;
    if (boxes && options_.box_keypoints &&
        (ok ? inliers_in_local_map_ < options_.box_check_below : (was_tracking || bridged_guess) && !rescue_waits)) {
      if (auto full = with_box_keypoints(frame, ok, boxes, result.static_boxes, bridged_guess)) {
        if (!ok) {
          result.method = "motion+boxes";
          result.rescued_with_boxes = true;
        }
        frame = std::move(*full);
        ok = true;
      }
    }
    if (!ok && odometry_bridge_) {
      // The map does not cover what this frame sees, but the last frame's depth points place it: track on
      // and make it a keyframe (below), so the next frame has map points here.
      frame = std::move(*odometry_bridge_);
      frame.reference_keyframe = reference_keyframe_;
      track_local_map(frame);  // adds the map points it can see; the odometry inliers carry the pose
      ok = true;
      bridged = true;
      result.method = "odometry";
    }
    odometry_bridge_.reset();
    if (!ok && boxes && options_.box_keypoints && !was_tracking && !rescue_waits) {
      // Lost, and the filter left too little to relocalise: the whole image may still show the map.
      if (auto full = relocalize_with_box_keypoints(frame, boxes)) {
        frame = std::move(*full);
        ok = true;
        result.method = "relocalization+boxes";
        result.rescued_with_boxes = true;
      }
    }
    // People hide the view (bridge), or it has cleared after a bridge onto what the map does not hold: with
    // depth, mapping goes on from the motion model's pose (the frame is a keyframe, still reported bridged).
    const bool hidden = people_share >= options_.bridge_min_people_share ||
                        (!ok && !options_.monocular && near_occluder_share(frame) >= options_.bridge_min_people_share);
    bool resumes = false;
    bool without_depth = false;  // the view has cleared, but the frame has too little depth to map on from
    if (!ok && after_bridge && motion && !options_.monocular && !localization_only_) {
      const auto max_points = static_cast<size_t>(options_.bridge_resume_max_map_points);
      if (!hidden) {
        const double bridge_age_s = frame.timestamp_s - motion->anchor_s;
        if (background_keypoints(frame) < static_cast<size_t>(options_.bridge_resume_min_depth_keypoints)) {
          without_depth = true;  // bridged on: the next frames may have the depth
        } else if (map_points_in_view < max_points) {
          resumes = true;
        } else if (options_.bridge_resume_recent_s > 0 && bridge_age_s <= options_.bridge_resume_recent_s) {
          spdlog::debug("frame {}: mapping goes on from a bridge of {:.2f} s ({} map points in view)", frame.id,
                        bridge_age_s, map_points_in_view);
          resumes = true;
        }
      } else if (options_.bridge_resume_min_keypoints > 0 &&
                 background_keypoints(frame) >= static_cast<size_t>(options_.bridge_resume_min_keypoints)) {
        map::Frame at_bridge = frame;
        at_bridge.cam_from_world = motion->at(frame.timestamp_s);
        resumes = map_points_near_keypoints(at_bridge) < max_points;
      }
    }
    const bool occluded = !ok && (hidden || resumes || without_depth) && (was_tracking || after_bridge) &&
                          bridge(frame, start_motion());
    if (occluded && resumes) {
      ok = bridged = resumed = true;  // a keyframe below
      result.method = "bridged";
    }
    state_ = ok ? TrackingState::kOk : occluded ? TrackingState::kBridged : TrackingState::kLost;
    if (!ok || bridged || after_bridge || (std::string_view(result.method) != "motion" && std::string_view(result.method) != "reference")) {
      odometry_chain_ = false;
    }
    if (!ok) result.method = occluded ? "bridged" : "lost";

    if (ok && dynamic_check_.enabled()) {
      // The pose is final: which of the matches moved (their map points may be culled), and the regions
      // around them. Dynamic keypoints are no longer tracked points.
      const bool skipped = result.dynamic.skipped;
      result.dynamic = dynamic_check_.update(frame, last_frame_ ? &*last_frame_ : nullptr);
      result.dynamic.skipped = skipped;
      dynamic_check_.free_space(frame, local_points_, result.dynamic);
      inliers_in_local_map_ = count_tracked_in_map(frame);
    }
    if (ok && boxes.box_of.size() == frame.size()) {  // the frame has its box keypoints back
      for (size_t i = 0; i < frame.size(); ++i) {
        if (boxes.box_of[i] >= 0 && frame.map_points[i] && !frame.outliers[i] && !frame.dynamic[i])
          ++result.box_matches;
      }
    }
    if (ok) {
      lost_frames_ = 0;
      last_tracked_s_ = frame.timestamp_s;
      last_bridged_s_.reset();
      bridge_motion_.reset();
      if (reanchor_) {  // relocalised while re-anchoring was possible
        reanchor_.reset();
        reanchor_initializer_.reset();
        frames_since_loss_.clear();
      }
      if (resumes) {
        velocity_ = geometry::SE3::exp(motion->twist_per_s * (frame.timestamp_s - last_frame_->timestamp_s));
      } else if (last_frame_ && last_frame_->cam_from_world && !after_bridge) {
        velocity_ = *frame.cam_from_world * last_frame_->cam_from_world->inverse();
      } else if (const auto m = after_bridge ? motion_after_bridge(frame.timestamp_s, motion) : std::nullopt;
                 m && last_frame_) {
        // Tracked again after bridged frames: on at the motion they followed.
        velocity_ = geometry::SE3::exp(m->twist_per_s * (frame.timestamp_s - last_frame_->timestamp_s));
      } else if (!options_.monocular) {
        // Relocalised after lost frames: the next frame is looked for near this pose (no velocity known),
        // so the motion model and its depth points can take it.
        velocity_ = geometry::SE3();
      } else {
        velocity_.reset();
      }
      bridge_recent_motion_.reset();
      if (!resumed) {
        recent_poses_.push_back({frame.timestamp_s, *frame.cam_from_world, inliers_in_local_map_});
        if (!options_.monocular) scene_depth_m_ = inlier_median_depth(frame);
        while (recent_poses_.size() > 30) recent_poses_.pop_front();
      } else {
        recent_poses_.clear();
      }
      // Visual-odometry matches (points created only for the last frame) are not map points.
      for (auto& p : frame.map_points) {
        if (p && p->num_observations() < 1) p.reset();
      }
      temporal_points_.clear();
      // A bridged frame is a keyframe whenever one can be made: the map has no points where it looks.
      KeyframeDecision decision = localization_only_ || (result.rescued_with_boxes && !options_.box_rescue_keyframes)
                                      ? KeyframeDecision::kNo
                                  : bridged && !mapper_->is_paused() ? KeyframeDecision::kInsert
                                                                     : need_new_keyframe(frame);
      if (decision == KeyframeDecision::kWaitForMapper) {
        // Local mapping is behind and this frame needs a keyframe: wait for it rather than track on
        // without new points.
        const bool accepting = wait_for_mapper(map_lock, result);
        decision = accepting && !mapper_->is_paused() ? KeyframeDecision::kInsert : KeyframeDecision::kNo;
      }
      if (decision == KeyframeDecision::kInsert) {
        create_new_keyframe(frame);
        result.new_keyframe = true;
        if (options_.monocular && options_.max_wait_for_mapping_ms > 0) {
          next_frame_wait_ =
              inliers_in_local_map_ < options_.monocular_weak_tracking_inliers || options_.monocular_replay_waits
                  ? NextFrameWait::kMapped
                  : NextFrameWait::kNone;
        }
      }
      // Outliers are kept until here so that a new keyframe could still use them (as ORB-SLAM2).
      frame.discard_outliers();
      if (!frames_to_retry_.empty()) {
        if (options_.monocular_replay_waits && options_.max_wait_for_mapping_ms > 0 && result.new_keyframe) {
          // An unpaced replay localises them in the map as the mapper leaves it after this frame's keyframe
          // (which the mapper adds to the map's keyframes), not in whatever part of it the mapper has reached.
          wait_for_mapper(map_lock, result);
        }
        const auto first = retry_first_keyframe_;
        result.recovered = retry_frames_before_init();
        if (!result.recovered.empty()) result.recovered_reference = first;
      }
    } else if (occluded) {
      // People hide the view: the motion model's pose, and no clock towards a new map.
      velocity_.reset();
      if (!after_bridge) bridge_recent_motion_ = last_frame_motion(frame, velocity_at_start);
      bridge_motion_ = motion;
      last_bridged_s_ = frame.timestamp_s;
      bridged_seen_s_ = frame.timestamp_s;
      lost_frames_ = 0;
      result.bridged_cam_from_world = frame.cam_from_world;
      // Monocular, onto a view the map does not hold with background to see: a two-view map there now
      // rather than after the bridge (tracker_reanchor.cpp).
      if (reanchor_while_bridged(frame, motion, result)) {
        state_ = TrackingState::kOk;
        result.method = "reanchor";
        result.new_keyframe = true;
        result.bridged_cam_from_world.reset();
        bridge_motion_.reset();
      }
    } else {
      if (options_.monocular && lost_frames_ == 0) {
        if (reanchor_ && after_bridge) {
          reanchor_->lost_since_s = frame.timestamp_s;  // started while bridged: the clock runs from now
        } else {
          start_reanchor(after_bridge ? bridge_motion_ : recent_motion(frame, velocity_at_start), frame.timestamp_s);
        }
      }
      velocity_.reset();
      bridge_motion_.reset();
      recent_poses_.clear();
      ++lost_frames_;
      if (!last_tracked_s_) last_tracked_s_ = frame.timestamp_s;  // lost from its first frame (a new map)
      // The clock runs from the last frame with a pose; after a bridge, from when the view cleared.
      const double lost_s = std::abs(frame.timestamp_s - last_bridged_s_.value_or(*last_tracked_s_));
      if (reanchor_ && reanchor(frame, result)) {
        state_ = TrackingState::kOk;
        result.method = "reanchor";
        result.new_keyframe = true;
      } else if (!map_loaded_ &&
          map_->num_keyframes() <= static_cast<size_t>(options_.reset_if_lost_within_keyframes)) {
        spdlog::warn("tracking lost with only {} keyframes: resetting the map", map_->num_keyframes());
        result.map_reset = true;
      } else if (reanchor_) {
        // Re-anchoring may still place the camera in this map: no new map meanwhile.
      } else if (!map_loaded_ && options_.new_map_after_lost_s > 0 &&
                 lost_s >= options_.new_map_after_lost_s &&
                 lost_frames_ >= options_.new_map_after_lost_min_frames) {
        spdlog::warn("tracking lost for {} frames ({:.1f} s) without relocalising: starting a new map",
                     lost_frames_, lost_s);
        result.map_reset = true;
      }
    }
  }
  if (!frame.reference_keyframe) frame.reference_keyframe = reference_keyframe_;
  if (frame.cam_from_world && frame.reference_keyframe &&
      (state_ == TrackingState::kOk || state_ == TrackingState::kBridged)) {
    last_cam_from_reference_ = *frame.cam_from_world * frame.reference_keyframe->world_from_cam();
  }
  result.state = resumed ? TrackingState::kBridged : state_;
  if (resumed) result.bridged_cam_from_world = frame.cam_from_world;
  result.cam_from_world = result.state == TrackingState::kOk ? frame.cam_from_world : std::nullopt;
  result.reference_keyframe = frame.reference_keyframe;
  result.tracked_points = result.state == TrackingState::kOk ? inliers_in_local_map_ : 0;
  frame.depth_raw.release();  // the caller's image: not kept beyond this call
  last_frame_ = std::move(frame);
  return result;
}

// ---- relocalisation ----
bool Tracker::relocalize(map::Frame& frame) {
  std::vector<std::shared_ptr<map::KeyFrame>> candidates;
  if (vocabulary_) ensure_bow(frame, *vocabulary_);
  if (database_ && frame.features->has_bow()) {
    // Place recognition: keyframes that look like the frame.
    candidates = database_->relocalization_candidates(*frame.features);
  } else {
    // No vocabulary: the reference keyframe and its neighbours, then the most recent keyframes.
    std::unordered_set<uint64_t> seen;
    auto add = [&](const std::shared_ptr<map::KeyFrame>& kf) {
      if (kf && !kf->is_bad() && seen.insert(kf->id).second) candidates.push_back(kf);
    };
    if (reference_keyframe_) {
      add(reference_keyframe_);
      for (const auto& kf : reference_keyframe_->best_covisible(5)) add(kf);
    }
    const auto all = map_->keyframes();
    for (auto it = all.rbegin(); it != all.rend() && candidates.size() < 16; ++it) add(*it);
  }
  const auto keyframe = relocalizer_.relocalize(frame, candidates, options_.pose);
  if (!keyframe) return false;
  reference_keyframe_ = keyframe;
  frame.reference_keyframe = keyframe;
  last_relocalization_frame_id_ = frame.id;
  velocity_.reset();
  spdlog::debug("relocalised frame {} against keyframe {}", frame.id, keyframe->id);
  return true;
}

// ---- frame-to-frame tracking ----
void Tracker::replace_replaced_points(map::Frame& frame) const {
  for (auto& p : frame.map_points) {
    if (!p) continue;
    if (auto replacement = p->replaced_by()) p = replacement;
  }
}

void Tracker::update_last_frame() {
  map::Frame& last = *last_frame_;
  // The reference keyframe may have moved since (local BA): re-anchor the last pose to it.
  if (last.reference_keyframe && last_cam_from_reference_) {
    last.cam_from_world = *last_cam_from_reference_ * last.reference_keyframe->cam_from_world();
  }
  // Monocular: the last frame made a keyframe, so the points local mapping has triangulated in it since
  // are matched too, not only those the frame tracked. On fast turns they are most of what the next frame
  // can see of the map. (RGB-D and stereo keyframes take their depth points at creation, above all.)
  if (options_.monocular && last_keyframe_ && last_keyframe_frame_id_ == last.id &&
      !last_keyframe_->is_bad()) {
    for (size_t i = 0; i < last.size(); ++i) {
      if (last.map_points[i]) continue;
      const long k = last_keyframe_indices_.empty() ? static_cast<long>(i) : last_keyframe_indices_[i];
      if (k < 0) continue;
      auto point = last_keyframe_->map_point(static_cast<size_t>(k));
      if (point && !point->is_bad()) {
        last.map_points[i] = std::move(point);
        last.outliers[i] = false;
      }
    }
  }
  // RGB-D: create visual-odometry points from the last frame's close depth points that have no map point,
  // so the motion model has enough matches even in new areas.
  const auto& f = *last.features;
  std::vector<std::pair<float, size_t>> by_depth;
  for (size_t i = 0; i < f.size(); ++i) {
    if (f.depth_m[i] > 0 && !last.in_box[i]) by_depth.emplace_back(f.depth_m[i], i);
  }
  if (by_depth.empty()) return;
  std::sort(by_depth.begin(), by_depth.end());
  int created = 0;
  for (const auto& [depth, i] : by_depth) {
    auto& slot = last.map_points[i];
    if (!slot || slot->num_observations() < 1) {
      slot = point_from_depth(last, i);
      temporal_points_.push_back(slot);
    }
    ++created;
    if (depth > options_.close_depth_m && created > 100) break;
  }
}

int Tracker::optimize_pose(map::Frame& frame) {
  // Matches known to move (dynamic_check.h) have no say in the pose.
  dynamic_check_.inherit(frame, last_frame_ ? &*last_frame_ : nullptr);
  const auto initial_pose = frame.cam_from_world;
  const std::vector<bool> inherited = frame.dynamic;
  if (dynamic_check_.screen(frame, options_.pose) == 0) return optimize_frame_pose(frame, options_.pose);
  const std::vector<std::shared_ptr<map::MapPoint>> matches = frame.map_points;
  const int inliers = optimize_frame_pose(frame, options_.pose);
  int usable = 0;  // matches not known to move before the screening
  for (size_t i = 0; i < matches.size(); ++i) {
    if (matches[i] && !inherited[i]) ++usable;
  }
  if (inliers >= 50 && 2 * inliers >= usable) return inliers;
  // The trusted points' pose leaves most matches out: they may be movers (people outside the filter's
  // reach), or the trusted points may be (points on a person that reached the map). The ordinary
  // optimisation from the initial guess is tried too.
  const int trusted_screened = dynamic_check_.trusted_inliers(frame);
  const auto screened_pose = frame.cam_from_world;
  const std::vector<bool> screened_dynamic = frame.dynamic;
  const std::vector<bool> screened_outliers = frame.outliers;
  frame.cam_from_world = initial_pose;
  frame.dynamic = inherited;
  frame.map_points = matches;
  std::fill(frame.outliers.begin(), frame.outliers.end(), false);
  const int plain = optimize_frame_pose(frame, options_.pose);
  const int trusted_plain = dynamic_check_.trusted_inliers(frame);
  // Too little agrees with the trusted points' pose: the ordinary optimisation decides. Otherwise the
  // ordinary pose wins only where it holds more matches and keeps nearly as many trusted points (4 in 5):
  // movers that take it over leave the trusted points (long-seen background) as its outliers, while two
  // poses a few centimetres apart both keep most of them.
  if (inliers < 50 || (plain > inliers && 5 * trusted_plain >= 4 * trusted_screened)) return plain;
  frame.cam_from_world = screened_pose;
  frame.dynamic = screened_dynamic;
  frame.outliers = screened_outliers;
  return inliers;
}

bool Tracker::wait_for_mapper(std::unique_lock<std::mutex>& map_lock, TrackResult& result) {
  // The map is unlocked meanwhile, so that the mapper can write its bundle adjustment back.
  const auto wait_start = std::chrono::steady_clock::now();
  map_lock.unlock();
  const bool accepting = mapper_->wait_until_accepting(options_.max_wait_for_mapping_ms);
  map_lock.lock();
  result.waited_for_mapping_ms +=
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wait_start).count();
  return accepting;
}

int Tracker::count_tracked_in_map(const map::Frame& frame) const {
  int n = 0;
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    const auto& p = frame.map_points[i];
    if (p && !frame.outliers[i] && !p->is_bad() && p->num_observations() > 0) ++n;
  }
  return n;
}

// The occlusion bridge's motion: tracker_bridge.cpp; motion model, reference keyframe and local-map
// tracking: tracker_local_map.cpp; keyframe decisions and creation, RGB-D / stereo initialisation:
// tracker_keyframes.cpp; monocular parts: tracker_monocular.cpp.

}  // namespace crowdslam::tracking
