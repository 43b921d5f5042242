#pragma once
// The tracking state machine (ORB-SLAM2's Tracking::Track for RGB-D, written our way): initialisation,
// motion-model and reference-keyframe tracking, local-map tracking, and keyframe creation.
// Runs on the caller's thread; hands keyframes to a KeyframeConsumer (the local mapper).
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <utility>

#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/map/frame.h"
#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map.h"
#include "crowdslam/optim/pose_optimizer.h"
#include "crowdslam/tracking/dynamic_check.h"
#include "crowdslam/tracking/keyframe_consumer.h"
#include "crowdslam/tracking/monocular_initializer.h"
#include "crowdslam/tracking/relocalizer.h"

namespace crowdslam::loop {
class KeyframeDatabase;
}

namespace crowdslam::tracking {

// kBridged: people hid the view; the frame has the motion model's pose but is not tracked (see
// TrackerOptions::bridge_max_s).
enum class TrackingState { kNotInitialized, kOk, kLost, kBridged };
const char* to_string(TrackingState state);

struct TrackerOptions {
  double close_depth_m = 3.0;             // "close" points (ThDepth * baseline): reliable depth
  int min_init_features = 500;            // keypoints with depth needed to initialise (RGB-D)
  // Where the people filter took a share s of the frame's keypoints, min_init_features x (1 - s) of them
  // (as many as the frame would need before the filter), and at least this many.
  int min_init_static_features = 150;
  int max_frames_between_keyframes = 30;  // usually the camera fps
  // Backpressure: when a keyframe is needed urgently and local mapping is behind, tracking waits for it
  // up to this long (with the map unlocked) instead of going on without the keyframe and losing track.
  // 0 = never wait (ORB-SLAM2's behaviour). Sequential mode never needs to wait.
  double max_wait_for_mapping_ms = 1000.0;
  int min_frames_between_keyframes = 0;
  double motion_model_radius = 15.0;  // px at level 0 for the motion-model projection search
  double keyframe_window_radius = 50.0;
  double local_map_radius_factor = 3.0;  // RGB-D: larger windows when tracking the local map
  int max_local_keyframes = 80;
  // A keyframe is due when the frame tracks fewer than this fraction of its reference keyframe's points
  // (ORB-SLAM2 uses 0.75 for RGB-D; more keyframes measured better, see docs/RESULTS.md).
  double keyframe_reference_ratio = 0.9;
  // Monocular: a frame that tracks fewer map points than this is a few bad frames from being lost, so it
  // asks for a keyframe whatever the reference ratio says, and waits for a busy mapper (backpressure)
  // rather than going on without new points, and the next frame waits until the mapper has mapped that
  // keyframe (docs/MAPPING.md, "Keyframe policy"). 0 = off.
  int monocular_weak_tracking_inliers = 100;
  // Monocular, with max_wait_for_mapping_ms > 0: an unpaced replay waits for local mapping as sequential
  // mode would, so that it makes sequential mode's keyframes with its accuracy and throughput follows the
  // mapper's speed (docs/MAPPING.md, "Backpressure"): a keyframe that is due (the reference ratio)
  // while the mapper is busy is waited for, not skipped, and the frame after a keyframe waits until the
  // mapper has mapped that keyframe, its local BA included. Off
  // (a paced replay, a live camera): only urgent keyframes are waited for (overdue, weak tracking, under
  // half the reference's points).
  bool monocular_replay_waits = true;
  // RGB-D / stereo with keyframe_reference_min_found = 0 (the default counts frames, below): the reference
  // keyframe's points counted for that ratio are those seen by at least this many keyframes (ORB-SLAM2:
  // 3; 2 while the map has two keyframes; monocular keeps 3). With 3, a
  // threaded run whose keyframes thin out counts ever fewer points (they need three keyframes to count, and
  // the mapper culls points seen by fewer than three after two keyframes), so keyframes thin out further:
  // on the synthetic rooms 24-26 keyframes in 300 frames against 110-136 sequential, at 3x the ATE
  // (docs/DYNAMIC.md). With 2 the threaded rooms make 56-63.
  int keyframe_reference_min_observations = 2;
  // RGB-D / stereo, when > 0 (replaces the observation count above): the reference keyframe's points
  // counted are those tracking has matched in at least this many frames. With observations, a point
  // counts once a second keyframe sees it, but 30-40 % of those are not re-detected in the next frame
  // (ORB repeatability), so the ratio test failed on every frame and an idle mapper meant a keyframe
  // per frame (sequential bonn_crowd: 214 of 927); found counts are frames, not keyframes, so they
  // neither inflate with new keyframes nor thin out when keyframes are sparse (docs/RESULTS.md).
  int keyframe_reference_min_found = 3;
  int reset_if_lost_within_keyframes = 5;  // lost with so few keyframes: reset the map and start again
  // Lost for this many frames in a row without relocalising: start a new map (0 = never; ORB-SLAM2 stays
  // lost until the camera returns, ORB-SLAM3's Atlas starts a new map at once). The camera is somewhere the
  // map does not cover; a new map tracks it from here on, and the old map's poses stay in the outputs as
  // their own segment. Never with a loaded map. Measured in sensor time, so that a 3 Hz sequence (or
  // KITTI at 10 Hz) does not wait 30 frames (10 s, 100 m of driving) as a frame count tuned for 30 Hz
  // cameras did; at least `new_map_after_lost_min_frames` relocalisation attempts are made first.
  double new_map_after_lost_s = 1.0;
  int new_map_after_lost_min_frames = 3;
  // Monocular re-anchoring (docs/CROWDS.md#monocular-re-anchoring): lost in a map of more than
  // reset_if_lost_within_keyframes keyframes, each frame is also offered to a two-view initialisation
  // (relocalisation is tried first, as always). When one succeeds within `reanchor_max_s` of the loss
  // (after a bridge: of when the view cleared, as the new-map clock), its two keyframes join the same map
  // (method "reanchor"): placed where the motion tracked before the loss puts the initializer's reference
  // frame, and scaled so that the two views' baseline is the one that motion predicts (by the last
  // reference keyframe's median scene depth when the camera barely moved). No new map is started
  // meanwhile; after `reanchor_max_s` the new-map rule above applies.
  // 0 = off.
  double reanchor_max_s = 3.0;
  // RGB-D / stereo: a frame the motion model places with at least this many inliers among the last
  // frame's points, its depth points (visual odometry) included, is tracked even when it sees too few
  // map points for the local map, and becomes a keyframe at once, so the map gets points where the camera
  // is (method "odometry"). People covering the mapped part of the view, or the camera turning to walls
  // the map has not seen, otherwise lose a camera whose motion is well measured (0 = off).
  int odometry_bridge_min_inliers = 50;
  // Occlusion bridge (docs/CROWDS.md#total-occlusion): a frame that fails while the people filter took at
  // least `bridge_min_people_share` of its keypoints has too little static evidence to be judged; it gets
  // the motion model's pose (state "bridged", never counted as tracked), for up to `bridge_max_s` after
  // the last tracked frame. No new map is started meanwhile; the frames after it are tracked from the
  // reference keyframe or relocalised into the same map, and the lost clock starts when the view clears
  // (0 = off: such frames are lost).
  double bridge_max_s = 3.0;
  double bridge_min_people_share = 0.5;
  // With depth, a frame is hidden too when at least bridge_min_people_share of its keypoints with depth
  // (after the filter) are nearer than this fraction of the scene's median depth at the last tracked
  // frame: something close covers the view, a person the detector missed (filling the view from half a
  // metre, cut by the image's edges) or anything else (0 = off).
  double bridge_near_depth_ratio = 0.5;
  // The bridge moves on from the last frame tracked with at least this many local-map inliers, at the
  // mean velocity of such frames over the half second before it: as people close in, the last few frames
  // are tracked on little and their poses (and the frame-to-frame velocity) are the least trustworthy.
  int bridge_anchor_min_inliers = 100;
  // With depth, mapping goes on from the bridged pose when the view clears only where the local map holds
  // fewer than this many points in view (the camera turned while it was covered); where it holds more,
  // the frame is lost and relocalised instead: the map is there, and a keyframe at a drifted pose would
  // contradict it.
  int bridge_resume_max_map_points = 100;
  // ... and while people still cover at least bridge_min_people_share of the keypoints, when the frame
  // has at least this many keypoints with depth outside the person boxes (and not near, below): then the map points in view are
  // counted only where the frame has keypoints (a person in front hides the others), so a strip of
  // background between people that the map never saw carries tracking on (0 = only when the view clears).
  int bridge_resume_min_keypoints = 150;
  // With depth and the view clear, mapping also goes on from the bridged pose where the map does hold
  // the view when the bridge is this recent (its anchor, below, at most this long before the frame): a
  // pose a few frames old has drifted by millimetres, and a frame that fails there failed on its own
  // evidence (a person the detector missed, the map's points hidden behind it), which the frames after
  // it, tracked from its keyframe, recover from (0 = off).
  double bridge_resume_recent_s = 0.2;
  // With depth and the view clear, a frame after a bridge with fewer than this many keypoints with depth
  // off the people (and not near) has nothing to map on with (stereo finds no match on a view still
  // blurred or half covered): it is bridged on instead of resumed or lost (within bridge_max_s), so that
  // the next frames, which have the depth, can resume (0 = off).
  int bridge_resume_min_depth_keypoints = 50;
  // With depth, a frame tracked after bridged frames is rejected (still bridged) when its pose differs
  // from the bridge's by more than base + rate x the time since the bridge's anchor: the bridge drifts a
  // few centimetres in a second, a pose from matches on a missed person or on look-alike texture by
  // metres (0 base = no check).
  double bridge_gate_base_m = 0.1;
  double bridge_gate_m_per_s = 0.3;
  double bridge_gate_base_deg = 10.0;
  double bridge_gate_deg_per_s = 30.0;
  // A pose predicted without a measurement (a frame's after bridged frames) is first
  // refined on the local map searched in windows `prediction_radius_factor` times ORB-SLAM's base window
  // (wider than local_map_radius_factor), when at least `prediction_min_inliers` of those matches agree;
  // the usual local-map tracking then starts from the refined pose (0 = off).
  double prediction_radius_factor = 4.0;
  int prediction_min_inliers = 15;
  // Keypoints in person boxes (Tracker::track, BoxKeypoints): taken back for the pose when the filtered
  // frame tracks fewer than box_check_below points or fails, if they match map points seen at least
  // box_min_observations times (a depth observation counts twice) and judged moving at most once in
  // their last 8 checks, and agree with the pose of the keypoints outside the boxes (when those failed:
  // box_rescue_min_inliers inliers of the pose from the motion model; System uses 30 for monocular).
  bool box_keypoints = true;
  int box_check_below = 150;
  int box_min_observations = 2;
  int box_rescue_min_inliers = 50;
  // Whether box keypoints may track a frame the filtered keypoints failed on.
  bool box_rescue = true;
  // A frame that only box keypoints could place ("auto" with depth, System): the first three below off
  // and the last two set, its box keypoints place it and nothing else. Person points the map holds can
  // outvote the background's (a rescued keyframe's pose drifted 0.3 m in local BA).
  bool box_release = true;          // a box the evidence shows static is released (release_static_boxes)
  bool box_rescue_keyframes = true;  // a frame taken back by box keypoints may become a keyframe
  // Its pose must lie within this of the motion model's (0 = no limit).
  double box_rescue_gate_m = 0.0;
  double box_rescue_gate_deg = 0.0;
  // Not within this long after the last bridged frame (0 = no limit): after a bridge the map holds points
  // mapped on from the bridged pose, and such a frame is left to the bridge and its resume rules.
  double box_rescue_after_bridge_s = 0.0;
  optim::PoseOptimizerOptions pose;
  // Geometric dynamic check of the tracked keypoints (dynamic_check.h).
  DynamicCheckOptions dynamic;
  // Monocular: two-view initialisation, ORB-SLAM2's monocular keyframe policy, points only by
  // triangulation (local mapper). See tracker_monocular.cpp.
  bool monocular = false;
  MonocularInitializerOptions monocular_init;
  void check() const;
};

// The two-view initialisation's options for monocular re-anchoring (tracker_reanchor.cpp).
MonocularInitializerOptions reanchor_initializer_options(MonocularInitializerOptions options);

// Per-frame outcome, for statistics and trajectory output.
struct TrackResult {
  TrackingState state = TrackingState::kNotInitialized;
  std::optional<geometry::SE3> cam_from_world;
  std::shared_ptr<map::KeyFrame> reference_keyframe;
  bool new_keyframe = false;
  bool map_reset = false;
  int tracked_points = 0;  // inliers after local-map tracking
  int keypoints = 0;
  // "init", "motion", "reference", "relocalization", "motion+boxes", "odometry", "bridged", "reanchor",
  // "lost"
  const char* method = "";
  // State kBridged: the motion model's pose for the frame (not a tracked pose).
  std::optional<geometry::SE3> bridged_cam_from_world;
  // Share of the frame's keypoints the people filter took (0 without boxes).
  double people_share = 0;
  int box_matches = 0;   // keypoints in person boxes among the tracked points (BoxKeypoints)
  int static_boxes = 0;  // boxes whose keypoints the static map vouched for (released, see box_keypoints.cpp)
  // The filtered frame failed and the keypoints in boxes tracked it (method "motion+boxes").
  bool rescued_with_boxes = false;
  double waited_for_mapping_ms = 0;  // time this frame waited for local mapping to take its keyframe
  DynamicCheckStats dynamic;         // the geometric dynamic check of this frame (zeros when off or lost)
  // Earlier frames localised afterwards, as (frame id, cam_from_world), with the keyframe their poses
  // hang from in the trajectory (`recovered_reference`):
  // - monocular initialisation (method "init"): the frames offered to the initializer before this one
  //   (since the last reset, at most kMaxFramesBeforeInit) that could be localised in the new map. The
  //   initializer's reference frame is the first keyframe, not listed here. Frames before the reference
  //   that the two-view map could not localise are tried again once the map has grown
  //   (retry_frames_before_init); those found then are listed on that later frame's result;
  // - monocular re-anchoring (method "reanchor"): the frames lost since tracking was lost (at most
  //   kMaxFramesBeforeInit) that could be localised in the map with the two new keyframes, and the
  //   re-anchoring's reference frame (the first new keyframe, `recovered_reference`).
  std::vector<std::pair<uint64_t, geometry::SE3>> recovered;
  std::shared_ptr<map::KeyFrame> recovered_reference;
};

class Tracker {
 public:
  Tracker(const TrackerOptions& options, std::shared_ptr<map::Map> map, KeyframeConsumer* mapper);

  // The keypoints the people filter took out of a frame.
  struct BoxKeypoints {
    // The frame's features before the filter (built only when asked for).
    std::function<std::shared_ptr<const map::FrameFeatures>()> features;
    // Per keypoint of those features: its index in the filtered frame, -1 = in a person box, and the
    // box it is in (any numbering, -1 = outside the boxes).
    std::vector<long> filtered_index;
    std::vector<int> box_of;
    explicit operator bool() const { return static_cast<bool>(features); }
  };

  // Tracks one frame; `frame` is consumed (kept as the last frame).
  // `boxes` (optional, TrackerOptions::box_keypoints): when the filtered frame tracks few points or fails,
  // the keypoints in person boxes are matched to the trusted static map points of the local map (seen
  // often, not judged moving) and, if they agree with the pose of the keypoints outside the boxes (or,
  // when those failed, with the motion model through the pose optimisation's chi-square test), help the
  // pose. A false-positive box (a poster, a textured wall) covering most of the image then costs no
  // tracking, and static background a person box hides still counts; a person who moves does not agree.
  // Nothing in the map is made of keypoints in boxes (Frame::in_box). A frame the box keypoints rescued is
  // reported as method "motion+boxes".
  // `people_share`: the share of the frame's keypoints the people filter took (the occlusion bridge).
  TrackResult track(map::Frame frame, const BoxKeypoints& boxes = {}, double people_share = 0);

  // Place recognition for relocalisation (optional; not owned). With it, frames that have a bag of words
  // relocalise against the database's candidates; without it, against recent keyframes (brute force).
  void set_keyframe_database(const loop::KeyframeDatabase* database) { database_ = database; }
  // Vocabulary for bags of words computed on demand (see frame_bow.h): for keyframes, reference-keyframe
  // tracking and relocalisation. Without it only frames built with a bag of words use one.
  void set_vocabulary(std::shared_ptr<const bow::Vocabulary> vocabulary) {
    vocabulary_ = std::move(vocabulary);
  }

  // A map was loaded into the (so far empty) map: the next frame relocalises against it instead of
  // initialising, and the loaded map is never reset. With `localization_only` no keyframe is created
  // (so local mapping gets nothing and no point or keyframe is added or removed).
  void start_in_loaded_map(bool localization_only);
  [[nodiscard]] bool localization_only() const { return localization_only_; }

  [[nodiscard]] TrackingState state() const { return state_; }
  [[nodiscard]] const map::Frame* last_frame() const { return last_frame_ ? &*last_frame_ : nullptr; }
  void reset();

 private:
  bool initialize(map::Frame& frame, double people_share);
  bool initialize_monocular(map::Frame& frame);  // tracker_monocular.cpp
  // The two keyframes of a two-view map (initialisation or re-anchoring) to the mapper; tracking goes on
  // from the second, with `points` as the local map (tracker_monocular.cpp).
  void track_from_two_views(const std::shared_ptr<map::KeyFrame>& first, const std::shared_ptr<map::KeyFrame>& second,
                            map::Frame& frame, std::vector<std::shared_ptr<map::MapPoint>> points);
  // After a monocular initialisation from `init_frame`: the earlier frames in frames_before_init_ that
  // the new map localises (tracker_monocular.cpp).
  std::vector<std::pair<uint64_t, geometry::SE3>> localize_frames_before_init(const map::Frame& init_frame,
                                                                              uint64_t reference_id);
  // The frames before the initializer's reference that failed, tried again backwards from the earliest
  // localised frame once the map has kRetryKeyframes[k] keyframes (the mapper has triangulated more of
  // the first views than the two-view initialisation could). Each frame found is returned once.
  std::vector<std::pair<uint64_t, geometry::SE3>> retry_frames_before_init();
  [[nodiscard]] bool retry_before_init_due() const;
  // Waits (bounded) until local mapping takes keyframes, `map_lock` released meanwhile; adds the wait to
  // result.waited_for_mapping_ms. Returns whether the mapper accepts keyframes.
  bool wait_for_mapper(std::unique_lock<std::mutex>& map_lock, TrackResult& result);
  enum class KeyframeDecision { kNo, kInsert, kWaitForMapper };
  KeyframeDecision need_new_keyframe_monocular(const map::Frame& frame) const;  // tracker_monocular.cpp
  bool track_with_motion_model(map::Frame& frame);
  bool track_reference_keyframe(map::Frame& frame);
  bool track_local_map(map::Frame& frame);
  bool relocalize(map::Frame& frame);
  void update_last_frame();
  void replace_replaced_points(map::Frame& frame) const;
  void update_local_map(const map::Frame& frame);
  int optimize_pose(map::Frame& frame);
  KeyframeDecision need_new_keyframe(const map::Frame& frame) const;
  void create_new_keyframe(map::Frame& frame);
  // A point from keypoint `index`'s depth, observed by `keyframe` as its keypoint `keyframe_index`.
  std::shared_ptr<map::MapPoint> make_point_from_depth(const map::Frame& frame, size_t index,
                                                       const std::shared_ptr<map::KeyFrame>& keyframe,
                                                       size_t keyframe_index) const;
  int count_tracked_in_map(const map::Frame& frame) const;
  // The frame with its keypoints in boxes back (see track); nullopt when they do not help. A frame that
  // failed is searched from the motion model's pose, or without a velocity (after a bridge) from `guess`.
  std::optional<map::Frame> with_box_keypoints(const map::Frame& frame, bool tracked,
                                               const BoxKeypoints& boxes, int& static_boxes,
                                               const std::optional<geometry::SE3>& guess = std::nullopt);
  // The last frame with its box keypoints (depth only), and the evidence its box keypoints give about this
  // frame's: matched where the pose says (+1) or not (-1). See box_keypoints.cpp.
  void remember_box_frame(const map::Frame& full);
  void box_flow_evidence(const map::Frame& full, std::vector<int8_t>& flow) const;
  // Relocalisation of a lost frame with its keypoints in boxes back (see track); nullopt when it fails.
  std::optional<map::Frame> relocalize_with_box_keypoints(const map::Frame& frame, const BoxKeypoints& boxes);
  // The motion bridged frames follow: from the last reliably tracked frame (bridge_anchor_min_inliers) at
  // the mean velocity of the reliable frames before it; else from the last frame at `velocity` (its
  // velocity when the frame came).
  struct BridgeMotion {
    double anchor_s = 0;
    geometry::SE3 anchor;  // cam_from_world
    geometry::Vec6 twist_per_s = geometry::Vec6::Zero();
    [[nodiscard]] geometry::SE3 at(double t) const {
      return geometry::SE3::exp(twist_per_s * (t - anchor_s)) * anchor;
    }
  };
  [[nodiscard]] std::optional<BridgeMotion> bridge_motion(const map::Frame& frame,
                                                          const std::optional<geometry::SE3>& velocity) const;
  // Whether `frame` can be bridged (TrackerOptions::bridge_max_s): within bridge_max_s of the last tracked
  // frame, with a motion to follow. Sets the frame's pose from it (no matches) if so.
  bool bridge(map::Frame& frame, const std::optional<BridgeMotion>& motion) const;
  // With depth: whether the frame's pose, found after bridged frames, is within what the bridge's motion
  // can have drifted since its anchor (TrackerOptions::bridge_gate_*).
  [[nodiscard]] bool agrees_with_bridge(const map::Frame& frame, const BridgeMotion& motion) const;
  // How far a pose's camera centre (m) and viewing direction (degrees) lie from a predicted pose's (the
  // bridge's gate, the box rescue's gate).
  struct PoseGap {
    double metres = 0;
    double degrees = 0;
  };
  [[nodiscard]] static PoseGap pose_gap(const geometry::SE3& cam_from_world, const geometry::SE3& predicted);
  // On from the last frame at `velocity` (its velocity when the frame came).
  [[nodiscard]] std::optional<BridgeMotion> last_frame_motion(const map::Frame& frame,
                                                              const std::optional<geometry::SE3>& velocity) const;
  // The motion of bridged frames at time t: the last frame's before the bridge (bridge_recent_motion_)
  // within kRecentBridgeS of it, else `motion` (the bridge's).
  [[nodiscard]] std::optional<BridgeMotion> motion_after_bridge(double t, const std::optional<BridgeMotion>& motion) const;
  // A frame after bridged ones, in the local map of before the bridge: from where the last frame before
  // the bridge, moving on at its velocity, puts it (for kRecentBridgeS), then from where the bridge puts it
  // (`frame`'s pose, set by bridge()); each refined first (refine_predicted_pose). True when tracked
  // (frame then replaced). `guess` gets the best pose to search the keypoints in boxes from otherwise.
  bool track_after_bridge(map::Frame& frame, const std::optional<BridgeMotion>& motion,
                          std::optional<geometry::SE3>& guess);
  // TrackerOptions::prediction_radius_factor: refines frame.cam_from_world (a prediction) on the local
  // map's points matched in wide windows. The frame's matches are left empty. False (pose unchanged) when
  // too few agree.
  bool refine_predicted_pose(map::Frame& frame) const;
  // Local map points that `frame` (at its pose) would see where it has a keypoint within a search window.
  [[nodiscard]] size_t map_points_near_keypoints(const map::Frame& frame) const;
  // Keypoints with depth outside the person boxes and not nearer than the near-occluder depth
  // (bridge_near_depth_ratio x the scene's depth).
  [[nodiscard]] size_t background_keypoints(const map::Frame& frame) const;
  // Median camera depth of the frame's inlier map points (0 without any).
  [[nodiscard]] static double inlier_median_depth(const map::Frame& frame);
  // Share of the frame's keypoints with depth that are nearer than bridge_near_depth_ratio x the scene's
  // depth at the last tracked frame (0 when either is unknown).
  [[nodiscard]] double near_occluder_share(const map::Frame& frame) const;
  // The motion bridge_motion() would follow, also when the bridge is off (monocular re-anchoring).
  [[nodiscard]] std::optional<BridgeMotion> recent_motion(const map::Frame& frame,
                                                          const std::optional<geometry::SE3>& velocity) const;
  // Monocular re-anchoring (TrackerOptions::reanchor_max_s, tracker_reanchor.cpp): remembers the motion
  // and scene depth at the loss; then offers each lost frame to the two-view initialisation and, when it
  // succeeds, adds its two keyframes to the map where that motion puts them, and localises the frames lost
  // meanwhile in it (result.recovered). True when `frame` is tracked.
  void start_reanchor(const std::optional<BridgeMotion>& motion, double lost_since_s);
  bool reanchor(map::Frame& frame, TrackResult& result);
  // A monocular bridged frame (pose from `motion`) whose view the map does not hold but which keeps
  // enough background off the people (bridge_resume_min_keypoints, fewer than
  // bridge_resume_max_map_points map points near its keypoints) is offered to re-anchoring, started
  // then if need be. True when it re-anchored (`frame` tracked).
  bool reanchor_while_bridged(map::Frame& frame, const std::optional<BridgeMotion>& motion, TrackResult& result);

  TrackerOptions options_;
  std::shared_ptr<map::Map> map_;
  KeyframeConsumer* mapper_;
  Relocalizer relocalizer_;
  MonocularInitializer monocular_initializer_;
  MonocularInitializer reanchor_initializer_;  // its options: reanchor_initializer_options()
  DynamicCheck dynamic_check_;
  const loop::KeyframeDatabase* database_ = nullptr;
  std::shared_ptr<const bow::Vocabulary> vocabulary_;

  TrackingState state_ = TrackingState::kNotInitialized;
  std::optional<map::Frame> last_frame_;
  std::optional<geometry::SE3> velocity_;
  std::optional<geometry::SE3> last_cam_from_reference_;  // cam_from_world(current) * world_from_cam(last)
  std::shared_ptr<map::KeyFrame> reference_keyframe_;
  std::shared_ptr<map::KeyFrame> last_keyframe_;
  uint64_t last_keyframe_frame_id_ = 0;
  // Every frame since the last keyframe was tracked by the motion model or the reference keyframe (no
  // relocalisation, bridge or odometry bridge): the next keyframe's KeyFrame::odometry can be measured.
  bool odometry_chain_ = false;
  // Per keypoint of the frame that made last_keyframe_: its index in the keyframe (-1 = left out); empty
  // when the keyframe has the frame's keypoints as they are.
  std::vector<long> last_keyframe_indices_;
  uint64_t last_relocalization_frame_id_ = 0;
  // The two keyframes the last monocular re-anchoring made (ids; first > second when none).
  std::pair<uint64_t, uint64_t> reanchor_keyframe_ids_{1, 0};
  // What the next frame waits for after a monocular keyframe (Tracker::track): nothing, or the whole
  // mapping of it, local BA included (an unpaced replay, or after weak tracking).
  enum class NextFrameWait { kNone, kMapped };
  NextFrameWait next_frame_wait_ = NextFrameWait::kNone;
  int lost_frames_ = 0;                   // consecutive lost frames (new_map_after_lost_min_frames)
  std::optional<double> last_tracked_s_;  // timestamp of the last tracked frame (new_map_after_lost_s)
  std::optional<BridgeMotion> bridge_motion_;  // while bridging
  std::optional<BridgeMotion> bridge_recent_motion_;  // the last frame before the bridge at its velocity
  struct Reanchor {
    BridgeMotion motion;          // from the last pose before the loss
    double lost_since_s = 0;      // the first lost frame (after a bridge: when the view cleared), or
                                  // the bridged frame it started at
    double median_depth = 1;      // of the reference keyframe then
    std::shared_ptr<map::KeyFrame> keyframe;  // that reference keyframe (the new part's parent)
  };
  std::optional<Reanchor> reanchor_;  // while lost in a monocular map that may be re-anchored
  std::deque<map::Frame> frames_since_loss_;  // the lost frames while re-anchoring (oldest first)
  struct RecentPose {
    double timestamp_s = 0;
    geometry::SE3 cam_from_world;
    int inliers = 0;
  };
  std::deque<RecentPose> recent_poses_;  // the last tracked frames (bridge_motion)
  double scene_depth_m_ = 0;  // median depth of the last tracked frame's inliers (0: unknown)
  std::optional<double> last_bridged_s_;          // timestamp of the last bridged frame (the lost clock)
  std::optional<double> bridged_seen_s_;          // the same, kept after tracking resumes (box_rescue_after_bridge_s)
  int inliers_in_local_map_ = 0;
  size_t projected_local_points_ = 0;  // local map points in view in the last track_local_map
  bool map_loaded_ = false;
  bool localization_only_ = false;
  std::vector<std::shared_ptr<map::MapPoint>> temporal_points_;  // visual-odometry points of the last frame
  // This frame as the motion model placed it, when only the last frame's depth points held it
  // (odometry_bridge_min_inliers); taken if nothing else tracks the frame.
  std::optional<map::Frame> odometry_bridge_;
  std::optional<map::Frame> last_box_frame_;  // remember_box_frame
  std::vector<std::shared_ptr<map::KeyFrame>> local_keyframes_;
  std::vector<std::shared_ptr<map::MapPoint>> local_points_;
  // Monocular: the frames the initializer saw so far (localize_frames_before_init), oldest first.
  static constexpr size_t kMaxFramesBeforeInit = 60;
  std::deque<map::Frame> frames_before_init_;
  std::vector<std::pair<uint64_t, geometry::SE3>> recovered_before_init_;  // of the initialising frame
  // retry_frames_before_init: the failed earlier frames (oldest first), the first keyframe and the pose of
  // the frame after the newest of them relative to it, and how many retries were made.
  std::deque<map::Frame> frames_to_retry_;
  std::shared_ptr<map::KeyFrame> retry_first_keyframe_;  // the initializer's reference frame's keyframe
  geometry::SE3 retry_anchor_from_first_;
  geometry::SE3 retry_step_;  // cam_from_world(earlier) * world_from_cam(later) for one frame, last measured
  size_t retries_before_init_ = 0;
};

}  // namespace crowdslam::tracking
