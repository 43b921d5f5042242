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

}  // namespace crowdslam::tracking
