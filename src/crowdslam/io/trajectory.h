#pragma once
// Trajectory files: TUM (timestamp tx ty tz qx qy qz qw), KITTI (3x4 row-major per line, no stamps)
// and EuRoC csv (timestamp in ns, p_x p_y p_z, q_w q_x q_y q_z).
//
// Poses are world_from_cam (the camera's pose in the world), as in all three formats.
#include <string>
#include <vector>

#include "crowdslam/geometry/se3.h"

namespace crowdslam::io {

struct StampedPose {
  double timestamp_s = 0.0;
  geometry::SE3 world_from_cam;
};
using Trajectory = std::vector<StampedPose>;

enum class TrajectoryFormat { kTum, kKitti, kEuroc };

// Readers throw InputError naming file and line for malformed lines. TUM reading keeps the file's order.
Trajectory read_tum_trajectory(const std::string& path);
// KITTI files have no stamps: timestamps are taken from `timestamps` when given (must match in count),
// else the line index.
Trajectory read_kitti_trajectory(const std::string& path, const std::vector<double>& timestamps = {});
Trajectory read_euroc_trajectory(const std::string& path);
// Picks the reader by content (EuRoC: ns stamps and commas; KITTI: 12 fields; TUM: 8 fields). A KITTI file
// takes its timestamps from the times.txt beside it (the KITTI layout; a count that differs is an
// InputError), else the line index (with a warning).
Trajectory read_trajectory(const std::string& path);
// The format read_trajectory() would pick: EuRoC when a '#' header names "[ns]" or the first data line
// has commas, at least 8 fields and a stamp >= 1e11 (nanoseconds); else KITTI for 12 fields; else TUM
// (also for empty files).
TrajectoryFormat detect_trajectory_format(const std::string& path);
// "tum", "kitti", "euroc".
const char* to_string(TrajectoryFormat format);

// Writers are atomic (util/atomic_file.h). TUM: timestamp with 6 decimals, pose values with 9.
void write_tum_trajectory(const std::string& path, const Trajectory& trajectory);
void write_kitti_trajectory(const std::string& path, const Trajectory& trajectory);
void write_euroc_trajectory(const std::string& path, const Trajectory& trajectory);
void write_trajectory(const std::string& path, const Trajectory& trajectory, TrajectoryFormat format);
// The pieces the writers use, for files written line by line (the run's trajectory journal): the header
// ("" for KITTI) and one newline-terminated line per pose.
std::string trajectory_header(TrajectoryFormat format);
std::string format_trajectory_line(const StampedPose& pose, TrajectoryFormat format);
// "tum" | "kitti" | "euroc" (anything else: TUM).
TrajectoryFormat parse_trajectory_format(const std::string& name);

}  // namespace crowdslam::io
