// The occlusion bridge (TrackerOptions::bridge_max_s, docs/CROWDS.md#total-occlusion): the motion that
// frames people hide entirely follow until the view clears.
#include <cmath>

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
  if (!velocity || !last_frame_ || !last_frame_->cam_from_world) return std::nullopt;
  const double dt = frame.timestamp_s - last_frame_->timestamp_s;
  if (!(dt > 0)) return std::nullopt;
  return BridgeMotion{last_frame_->timestamp_s, *last_frame_->cam_from_world, velocity->log() / dt};
}

bool Tracker::bridge(map::Frame& frame, const std::optional<BridgeMotion>& motion) const {
  if (options_.bridge_max_s <= 0 || !motion || !last_tracked_s_) return false;
  if (std::abs(frame.timestamp_s - *last_tracked_s_) > options_.bridge_max_s) return false;
  frame.cam_from_world = motion->at(frame.timestamp_s);
  std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
  std::fill(frame.outliers.begin(), frame.outliers.end(), false);
  return true;
}

}  // namespace crowdslam::tracking
