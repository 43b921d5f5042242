#pragma once
// Motion-only pose optimisation of a frame against its matched map points (shared by tracking and
// relocalisation).
#include "crowdslam/map/frame.h"
#include "crowdslam/optim/pose_optimizer.h"

namespace crowdslam::tracking {

// Optimises frame.cam_from_world (which must be set) and marks frame.outliers; returns the number of
// inliers (0 when the optimiser had too few observations; the pose is then unchanged).
int optimize_frame_pose(map::Frame& frame, const optim::PoseOptimizerOptions& options);

// Clears the slots of outlier matches (and their flags); returns how many kept matches are map points with
// at least one observation (visual-odometry points of the last frame do not count).
int discard_outliers_count_map_points(map::Frame& frame);

// Keypoint i's error against map point `point` seen from `pose`: reprojection plus, when the keypoint has
// a right coordinate (stereo / depth), disparity, weighed by the keypoint's level as the pose optimisation
// weighs it (a chi-square value with 3 dof with depth, 2 without); a point behind the camera is far off.
constexpr double kMatchChi2Mono = 5.991;    // 2 dof, 95 %
constexpr double kMatchChi2Stereo = 7.815;  // 3 dof, 95 %
struct MatchResidual {
  double chi2 = 0;
  double threshold = kMatchChi2Mono;  // the 95 % chi-square threshold for its degrees of freedom
};
// A point for one frame only (no keyframe, id 0) where keypoint i's depth places it, with its descriptor:
// the visual-odometry points of the motion model and the box keypoints' frame-to-frame evidence.
// Requires frame.cam_from_world and a depth for i.
std::shared_ptr<map::MapPoint> point_from_depth(const map::Frame& frame, size_t i);

MatchResidual match_residual(const map::Frame& frame, size_t i, const map::MapPoint& point, const geometry::SE3& pose);

}  // namespace crowdslam::tracking
