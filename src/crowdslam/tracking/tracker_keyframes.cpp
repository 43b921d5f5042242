// The tracker's keyframe decisions (RGB-D / stereo; the monocular policy is in tracker_monocular.cpp) and
// the making of a keyframe from the current frame, with its points from depth; the RGB-D / stereo
// initialisation from one frame with depth.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "crowdslam/map/map_point.h"
#include "crowdslam/tracking/frame_bow.h"
#include "crowdslam/tracking/tracker.h"

namespace crowdslam::tracking {

namespace {
// RGB-D / stereo: frames after a relocalisation that must each keep 50 inliers before a keyframe may be
// made from the relocalised pose (need_new_keyframe).
constexpr uint64_t kRelocConfirmFrames = 5;
}  // namespace

Tracker::KeyframeDecision Tracker::need_new_keyframe(const map::Frame& frame) const {
  if (options_.monocular) return need_new_keyframe_monocular(frame);
  if (mapper_->is_paused()) return KeyframeDecision::kNo;
  const size_t num_keyframes = map_->num_keyframes();
  const auto max_frames = static_cast<uint64_t>(options_.max_frames_between_keyframes);
  const bool recently_relocalized = last_relocalization_frame_id_ > 0 &&
                                    frame.id < last_relocalization_frame_id_ + max_frames &&
                                    num_keyframes > max_frames;
  // The reference keyframe's points that count: found by tracking in enough frames (default), or seen by
  // enough keyframes (keyframe_reference_min_found = 0).
  const int min_found = options_.keyframe_reference_min_found;
  const int min_observations = num_keyframes <= 2 ? 2 : options_.keyframe_reference_min_observations;
  const int reference_matches = !reference_keyframe_ ? 0
                                : min_found > 0      ? reference_keyframe_->found_map_points(min_found)
                                                : reference_keyframe_->tracked_map_points(min_observations);
  const bool mapper_idle = mapper_->accepts_keyframes();

  // Close points (reliable depth) tracked vs. not tracked.
  int tracked_close = 0;
  int untracked_close = 0;
  const auto& f = *frame.features;
  for (size_t i = 0; i < f.size(); ++i) {
    if (f.depth_m[i] > 0 && f.depth_m[i] < options_.close_depth_m && !frame.dynamic[i] && !frame.in_box[i]) {
      if (frame.map_points[i] && !frame.outliers[i]) {
        ++tracked_close;
      } else {
        ++untracked_close;
      }
    }
  }
  const bool need_close = tracked_close < 100 && untracked_close > 70;
  // ORB-SLAM2 makes no keyframe in the second after a relocalisation (its pose may be wrong). Each frame
  // there keeps 50 inliers (track_local_map), so when the camera moves on into what the map has not seen
  // and the close points run out, a keyframe from depth is what keeps tracking alive: measured on the
  // synthetic stereo crowds, where tracking otherwise died 7 frames after relocalising (docs/RESULTS.md).
  const bool reloc_confirmed = frame.id >= last_relocalization_frame_id_ + kRelocConfirmFrames;
  if (recently_relocalized && !(need_close && reloc_confirmed)) return KeyframeDecision::kNo;
  const double ref_ratio = num_keyframes < 2 ? 0.4 : options_.keyframe_reference_ratio;
  const bool c1a = frame.id >= last_keyframe_frame_id_ + max_frames;
  const bool c1b =
      frame.id >= last_keyframe_frame_id_ + static_cast<uint64_t>(options_.min_frames_between_keyframes) &&
      mapper_idle;
  const bool c1c = inliers_in_local_map_ < reference_matches * 0.25 || need_close;
  const bool c2 =
      (inliers_in_local_map_ < reference_matches * ref_ratio || need_close) && inliers_in_local_map_ > 15;
  if (!((c1a || c1b || c1c) && c2)) return KeyframeDecision::kNo;
  if (mapper_idle) return KeyframeDecision::kInsert;
  mapper_->interrupt_bundle_adjustment();
  // RGB-D / stereo never wait for the mapper: a keyframe's new points come from depth, made here by
  // tracking, so tracking does not run out of points when local mapping is behind (measured on
  // bonn_crowd: waiting when three keyframes were queued cost 0.7 s of a 20 s run and gained nothing).
  return mapper_->queued_keyframes() < 3 ? KeyframeDecision::kInsert : KeyframeDecision::kNo;
}

void Tracker::create_new_keyframe(map::Frame& frame) {
  // Dynamic keypoints (dynamic_check.h) and keypoints in person boxes are left out of the keyframe, so
  // nothing in the map (points from depth here, triangulation and fusion in local mapping) is made of them.
  std::vector<long> to_keyframe;
  std::shared_ptr<const map::FrameFeatures> features = frame.features;
  std::vector<bool> left_out(frame.size(), false);
  bool any_left_out = false;
  for (size_t i = 0; i < frame.size(); ++i) {
    left_out[i] = frame.dynamic[i] || frame.in_box[i];
    any_left_out = any_left_out || left_out[i];
  }
  if (any_left_out) {
    features = features_without(*frame.features, left_out, to_keyframe, vocabulary_.get());
  } else {
    if (vocabulary_) ensure_bow(frame, *vocabulary_);  // keyframes carry their bag of words
    features = frame.features;
    to_keyframe.resize(frame.size());
    std::iota(to_keyframe.begin(), to_keyframe.end(), 0L);
  }
  auto keyframe =
      std::make_shared<map::KeyFrame>(map_->next_keyframe_id(), frame.id, frame.timestamp_s, frame.camera,
                                      frame.levels, features, *frame.cam_from_world);
  // The keyframe takes the frame's current matches (the mapper adds the observations).
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    if (to_keyframe[i] >= 0 && frame.map_points[i] && !frame.outliers[i] && !frame.map_points[i]->is_bad()) {
      keyframe->add_map_point(static_cast<size_t>(to_keyframe[i]), frame.map_points[i]);
    }
  }
  // New points from the closest depth measurements without a map point.
  const auto& f = *frame.features;
  std::vector<std::pair<float, size_t>> by_depth;
  for (size_t i = 0; i < f.size(); ++i) {
    if (f.depth_m[i] > 0) by_depth.emplace_back(f.depth_m[i], i);
  }
  std::sort(by_depth.begin(), by_depth.end());
  int count = 0;
  for (const auto& [depth, i] : by_depth) {
    if (to_keyframe[i] < 0) continue;
    const auto& existing = frame.map_points[i];
    if (!existing || existing->num_observations() < 1 || frame.outliers[i]) {
      frame.outliers[i] = false;
      frame.map_points[i] = make_point_from_depth(frame, i, keyframe, static_cast<size_t>(to_keyframe[i]));
    }
    ++count;
    if (depth > options_.close_depth_m && count > 100) break;
  }
  // make_point_from_depth already linked the new points; registered observations for the rest come
  // from the mapper (process_new_keyframe).
  // With depth, the pose relative to the keyframe before, when every frame since was tracked: tracking
  // placed it with the last frame's depth points too, which never reach the map (KeyFrame::odometry).
  if (!options_.monocular && odometry_chain_ && last_keyframe_ && !last_keyframe_->is_bad()) {
    const double median_depth = keyframe->scene_median_depth();
    if (median_depth > 0) {
      keyframe->odometry =
          map::KeyFrame::Odometry{last_keyframe_->id, keyframe->cam_from_world() * last_keyframe_->world_from_cam(),
                                  median_depth};
    }
  }
  odometry_chain_ = true;
  reference_keyframe_ = keyframe;
  frame.reference_keyframe = keyframe;
  last_keyframe_ = keyframe;
  last_keyframe_frame_id_ = frame.id;
  if (any_left_out) {
    last_keyframe_indices_ = std::move(to_keyframe);
  } else {
    last_keyframe_indices_.clear();
  }
  mapper_->insert_keyframe(keyframe);
}

// ---- initialisation (RGB-D / stereo: one frame with depth) ----
bool Tracker::initialize(map::Frame& frame, double people_share) {
  if (vocabulary_) ensure_bow(frame, *vocabulary_);  // the first keyframe carries its bag of words
  const auto& f = *frame.features;
  int with_depth = 0;
  for (size_t i = 0; i < f.size(); ++i) {
    if (f.depth_m[i] > 0) ++with_depth;
  }
  // A crowd takes part of the view: the frame needs what it would before the filter (ORB-SLAM2's 500 of
  // 1,000 keypoints, a textured enough view) in proportion to what the filter left.
  const double left = 1.0 - std::clamp(people_share, 0.0, 1.0);
  const int needed = std::min(options_.min_init_features,
                              std::max(options_.min_init_static_features,
                                       static_cast<int>(std::ceil(options_.min_init_features * left))));
  if (with_depth < needed) return false;

  frame.cam_from_world = geometry::SE3::identity();
  auto keyframe =
      std::make_shared<map::KeyFrame>(map_->next_keyframe_id(), frame.id, frame.timestamp_s, frame.camera,
                                      frame.levels, frame.features, *frame.cam_from_world);
  map_->add_keyframe(keyframe);
  for (size_t i = 0; i < f.size(); ++i) {
    if (f.depth_m[i] <= 0) continue;
    auto point = make_point_from_depth(frame, i, keyframe, i);
    frame.map_points[i] = point;
  }
  spdlog::info("map initialised with {} points at frame {}", map_->num_map_points(), frame.id);
  mapper_->insert_keyframe(keyframe);
  last_keyframe_ = keyframe;
  last_keyframe_frame_id_ = frame.id;
  odometry_chain_ = true;
  reference_keyframe_ = keyframe;
  frame.reference_keyframe = keyframe;
  local_keyframes_ = {keyframe};
  local_points_ = keyframe->valid_map_points();
  inliers_in_local_map_ = static_cast<int>(local_points_.size());
  return true;
}

std::shared_ptr<map::MapPoint> Tracker::make_point_from_depth(const map::Frame& frame, size_t index,
                                                              const std::shared_ptr<map::KeyFrame>& keyframe,
                                                              size_t keyframe_index) const {
  const auto& f = *frame.features;
  const geometry::Vec2 pixel(f.keys_un[index].pt.x, f.keys_un[index].pt.y);
  const geometry::Vec3 world =
      frame.cam_from_world->inverse() * frame.camera->unproject(pixel, f.depth_m[index]);
  auto point = std::make_shared<map::MapPoint>(map_->next_map_point_id(), world, keyframe, frame.id);
  point->add_observation(keyframe, keyframe_index);
  keyframe->add_map_point(keyframe_index, point);
  point->compute_distinctive_descriptor();
  point->update_normal_and_depth();
  map_->add_map_point(point);
  return point;
}

}  // namespace crowdslam::tracking
