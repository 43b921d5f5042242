// The occlusion bridge (TrackerOptions::bridge_max_s, docs/CROWDS.md#total-occlusion): the motion that
// frames people hide entirely follow until the view clears.
#include <algorithm>
#include <cmath>
#include <vector>

#include "crowdslam/tracking/localize_frames.h"

#include "crowdslam/tracking/tracker.h"

namespace crowdslam::tracking {

std::optional<Tracker::BridgeMotion> Tracker::bridge_motion(const map::Frame& frame,
                                                             const std::optional<geometry::SE3>& velocity) const {
  if (options_.bridge_max_s <= 0) return std::nullopt;
  return recent_motion(frame, velocity);
}

std::optional<Tracker::BridgeMotion> Tracker::recent_motion(const map::Frame& frame,
                                                             const std::optional<geometry::SE3>& velocity) const {
  // The last reliable frame, and the earliest reliable one within half a second before it.
  const RecentPose* anchor = nullptr;
  const RecentPose* base = nullptr;
  for (auto it = recent_poses_.rbegin(); it != recent_poses_.rend(); ++it) {
    if (it->inliers < options_.bridge_anchor_min_inliers) continue;
    if (!anchor) {
      anchor = &*it;
    } else if (anchor->timestamp_s - it->timestamp_s <= 0.5) {
      base = &*it;
    }
  }
  if (anchor && base && anchor->timestamp_s > base->timestamp_s) {
    const geometry::SE3 step = anchor->cam_from_world * base->cam_from_world.inverse();
    return BridgeMotion{anchor->timestamp_s, anchor->cam_from_world,
                        step.log() / (anchor->timestamp_s - base->timestamp_s)};
  }
  // Not enough reliable frames: on from the last frame at its velocity.
  return last_frame_motion(frame, velocity);
}

std::optional<Tracker::BridgeMotion> Tracker::last_frame_motion(const map::Frame& frame,
                                                                 const std::optional<geometry::SE3>& velocity) const {
  if (!velocity || !last_frame_ || !last_frame_->cam_from_world) return std::nullopt;
  const double dt = frame.timestamp_s - last_frame_->timestamp_s;
  if (!(dt > 0)) return std::nullopt;
  return BridgeMotion{last_frame_->timestamp_s, *last_frame_->cam_from_world, velocity->log() / dt};
}

namespace {
// The bridge follows the motion of the frames tracked on many points before the occlusion (up to half a
// second before it). When people close in over a few frames, those last frames are tracked on little,
// but a short gap after them is still best bridged by their own motion.
constexpr double kRecentBridgeS = 0.5;
}  // namespace

std::optional<Tracker::BridgeMotion> Tracker::motion_after_bridge(double t,
                                                                   const std::optional<BridgeMotion>& motion) const {
  if (bridge_recent_motion_ && t - bridge_recent_motion_->anchor_s <= kRecentBridgeS) return bridge_recent_motion_;
  return motion;
}

bool Tracker::track_after_bridge(map::Frame& frame, const std::optional<BridgeMotion>& motion,
                                 std::optional<geometry::SE3>& guess) {
  std::vector<geometry::SE3> predictions;
  if (bridge_recent_motion_ && frame.timestamp_s - bridge_recent_motion_->anchor_s <= kRecentBridgeS) {
    predictions.push_back(bridge_recent_motion_->at(frame.timestamp_s));
  }
  if (motion) predictions.push_back(motion->at(frame.timestamp_s));
  std::optional<geometry::SE3> refined;
  for (const auto& prediction : predictions) {
    map::Frame candidate = frame;
    candidate.cam_from_world = prediction;
    candidate.reference_keyframe = reference_keyframe_;
    if (refine_predicted_pose(candidate) && !refined) refined = candidate.cam_from_world;
    if (track_local_map(candidate)) {
      frame = std::move(candidate);
      return true;
    }
  }
  if (refined) {
    guess = refined;
  } else if (!predictions.empty()) {
    guess = predictions.front();
  }
  return false;
}

bool Tracker::bridge(map::Frame& frame, const std::optional<BridgeMotion>& motion) const {
  if (options_.bridge_max_s <= 0 || !motion || !last_tracked_s_) return false;
  if (std::abs(frame.timestamp_s - *last_tracked_s_) > options_.bridge_max_s) return false;
  frame.cam_from_world = motion->at(frame.timestamp_s);
  std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
  std::fill(frame.outliers.begin(), frame.outliers.end(), false);
  return true;
}

bool Tracker::refine_predicted_pose(map::Frame& frame) const {
  // A bridged pose follows the motion of up to half a second before the occlusion, frames ago: a few
  // pixels off already exceeds the local-map window (2.5-4 px at level 0 in monocular), and a frame whose
  // static part is a strip between people then finds too few of its points there.
  if (!(options_.prediction_radius_factor > 0) || !frame.cam_from_world) return false;
  map::Frame probe = frame;
  if (match_projected_and_optimize(probe, local_points_, options_.prediction_radius_factor, options_.pose) <
      options_.prediction_min_inliers) {
    return false;
  }
  frame.cam_from_world = probe.cam_from_world;
  std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
  std::fill(frame.outliers.begin(), frame.outliers.end(), false);
  return true;
}

Tracker::PoseGap Tracker::pose_gap(const geometry::SE3& cam_from_world, const geometry::SE3& predicted) {
  // Camera centres and viewing rotations compared (cam_from_world: the centre is -R^T t).
  const geometry::SE3 world_from_cam = cam_from_world.inverse();
  const geometry::SE3 world_from_predicted = predicted.inverse();
  return {(world_from_cam.translation() - world_from_predicted.translation()).norm(),
          geometry::rotation_angle(world_from_predicted.rotation_matrix().transpose() * world_from_cam.rotation_matrix()) *
              180.0 / M_PI};
}

bool Tracker::agrees_with_bridge(const map::Frame& frame, const BridgeMotion& motion) const {
  if (!(options_.bridge_gate_base_m > 0) || !frame.cam_from_world) return true;
  const double elapsed_s = std::max(0.0, frame.timestamp_s - motion.anchor_s);
  const PoseGap gap = pose_gap(*frame.cam_from_world, motion.at(frame.timestamp_s));
  return gap.metres <= options_.bridge_gate_base_m + options_.bridge_gate_m_per_s * elapsed_s &&
         gap.degrees <= options_.bridge_gate_base_deg + options_.bridge_gate_deg_per_s * elapsed_s;
}

size_t Tracker::map_points_near_keypoints(const map::Frame& frame) const {
  if (!frame.cam_from_world) return 0;
  const auto& f = *frame.features;
  size_t near = 0;
  for (const auto& p : local_points_) {
    if (p->is_bad()) continue;
    const auto projection = frame.project(*p, 0.5);
    if (!projection) continue;
    // ORB-SLAM's base window (4 px at level 0) as widened for tracking the local map.
    const double radius = 4.0 * options_.local_map_radius_factor * frame.levels->scale[projection->predicted_level];
    if (!f.grid.features_in_area(f.keys_un, static_cast<float>(projection->u), static_cast<float>(projection->v),
                                 static_cast<float>(radius))
             .empty()) {
      ++near;
    }
  }
  return near;
}

double Tracker::inlier_median_depth(const map::Frame& frame) {
  if (!frame.cam_from_world) return 0;
  std::vector<double> depths;
  depths.reserve(frame.map_points.size());
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    const auto& p = frame.map_points[i];
    if (!p || frame.outliers[i] || p->is_bad()) continue;
    const double z = (*frame.cam_from_world * p->world()).z();
    if (z > 0) depths.push_back(z);
  }
  if (depths.empty()) return 0;
  const auto middle = depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2);
  std::nth_element(depths.begin(), middle, depths.end());
  return *middle;
}

double Tracker::near_occluder_share(const map::Frame& frame) const {
  if (!(options_.bridge_near_depth_ratio > 0) || !(scene_depth_m_ > 0)) return 0;
  const double near = options_.bridge_near_depth_ratio * scene_depth_m_;
  const auto& f = *frame.features;
  size_t with_depth = 0;
  size_t nearer = 0;
  for (size_t i = 0; i < f.size(); ++i) {
    if (!(f.depth_m[i] > 0)) continue;
    ++with_depth;
    if (f.depth_m[i] < near) ++nearer;
  }
  return with_depth == 0 ? 0.0 : static_cast<double>(nearer) / static_cast<double>(with_depth);
}

size_t Tracker::background_keypoints(const map::Frame& frame) const {
  const double near = options_.bridge_near_depth_ratio * scene_depth_m_;
  const auto& f = *frame.features;
  size_t n = 0;
  for (size_t i = 0; i < f.size(); ++i) {
    if (f.depth_m[i] > 0 && f.depth_m[i] >= near && !frame.in_box[i] && !frame.dynamic[i]) ++n;
  }
  return n;
}

}  // namespace crowdslam::tracking
