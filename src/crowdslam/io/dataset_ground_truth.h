#pragma once
// Ground truth of the dataset layouts (internal to io). Poses are world_from_cam, stamps in seconds.
// Thin wrappers so the layout readers share one place that knows the trajectory formats.
#include <string>
#include <vector>

#include "crowdslam/io/trajectory.h"

namespace crowdslam::io {

// TUM "t tx ty tz qx qy qz qw" lines; '#' comments. InputError names file and line.
Trajectory load_tum_ground_truth(const std::string& path);
// KITTI 12 numbers per line (row-major 3x4); stamps must have the same count.
Trajectory load_kitti_ground_truth(const std::string& path, const std::vector<double>& stamps);
// EuRoC state_groundtruth_estimate0/data.csv: t_ns, p_x, p_y, p_z, q_w, q_x, q_y, q_z, ...
Trajectory load_euroc_ground_truth(const std::string& path);

}  // namespace crowdslam::io
