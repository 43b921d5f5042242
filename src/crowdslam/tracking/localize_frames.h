#pragma once
// Frames that could not be tracked when they came, localised afterwards in a map that has grown around
// them: those before a monocular initialisation and those lost before a monocular re-anchoring
// (tracker_monocular.cpp, tracker_reanchor.cpp).
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "crowdslam/map/frame.h"
#include "crowdslam/optim/pose_optimizer.h"

namespace crowdslam::tracking {

using FramePoses = std::vector<std::pair<uint64_t, geometry::SE3>>;  // (frame id, cam_from_world)

// The pose a fraction `t` of the way from `a` to `b` (camera centres on the line, rotations slerped).
geometry::SE3 interpolate_pose(const geometry::SE3& a, const geometry::SE3& b, double t);

// `frame`'s matches replaced by those of `points` projected from its pose (searched with
// match::search_local_points' `radius_factor`), and its pose optimised on them; the inliers.
int match_projected_and_optimize(map::Frame& frame, const std::vector<std::shared_ptr<map::MapPoint>>& points,
                                 double radius_factor, const optim::PoseOptimizerOptions& options);

// `frames` holds at most `max` frames: `frame` is appended, the oldest dropped.
void keep_last_frames(std::deque<map::Frame>& frames, const map::Frame& frame, size_t max);

// `frame` matched by projection to `points` from the pose guess, wide then narrow, and its pose optimised;
// it counts when it keeps the 50 inliers a pose from new matches needs (as relocalisation).
std::optional<geometry::SE3> localize_in_map(map::Frame frame, const geometry::SE3& guess,
                                             const std::vector<std::shared_ptr<map::MapPoint>>& points,
                                             const optim::PoseOptimizerOptions& options);

// The longest run of failing frames a last pass over frames localised afterwards skips (people in front of
// the camera for a moment): the last retry before a monocular initialisation, and a re-anchoring.
inline constexpr double kLocalizeMaxGapS = 0.5;

// Frames before `later` (newest last in `frames`, which keeps those that fail), each from the pose of the
// frame after it moved by the last measured step. `step` is cam_from_world(earlier) * world_from_cam(later)
// for one frame interval, as last measured. Stops at a failure more than `max_gap_s` before the last frame
// localised (0: at the first failure); a failed frame within that is skipped, and the frame before it is
// guessed on by the same step from where the failed one was guessed. On return `later` and `step` are
// those of the oldest frame localised; `frames` holds, oldest first, the frames not tried and those skipped.
FramePoses localize_backwards(std::deque<map::Frame>& frames, geometry::SE3& later, geometry::SE3& step,
                              const std::vector<std::shared_ptr<map::MapPoint>>& points,
                              const optim::PoseOptimizerOptions& options, double max_gap_s = 0.0);

// Frames around a two-view reconstruction whose reference frame `reference_id` (keyframe at `first_pose`,
// time t0) and second view (`last_pose`, time t1) are in the map. Frames after the reference are guessed
// by interpolating in time between the two; those before it, newest first, backwards from the reference
// by the motion between the two views extrapolated to the frame before. Frames between the views that
// fail are dropped; those before the reference that fail stay in `left` (oldest first), with `later` and
// `step` where localize_backwards would go on from (`max_gap_s` as there: with a gap, `left` is not for
// going on from).
struct AroundTwoViews {
  FramePoses recovered;  // sorted by frame id
  std::deque<map::Frame> left;
  geometry::SE3 later;
  geometry::SE3 step;
};
AroundTwoViews localize_around_two_views(std::deque<map::Frame> frames, uint64_t reference_id,
                                         const geometry::SE3& first_pose, double t0,
                                         const geometry::SE3& last_pose, double t1,
                                         const std::vector<std::shared_ptr<map::MapPoint>>& points,
                                         const optim::PoseOptimizerOptions& options, double max_gap_s = 0.0);

}  // namespace crowdslam::tracking
