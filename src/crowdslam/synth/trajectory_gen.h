#pragma once
// Camera trajectories of the synthetic room (world z up, room centred at the origin on the floor).
//
// loop:     one or more closed loops (one per ~300 frames) on an ellipse around the room centre, looking
//           outwards; the last frame's pose equals the first one's exactly.
// line:     back-and-forth translation along x looking at the +y wall.
// sweep:    a translation along x with a +-70 degree pan towards the side it moves to.
// handheld: loop plus a small smooth shake (harmonics of the loop, so it still closes exactly).
#include <cstdint>

#include "crowdslam/io/trajectory.h"
#include "crowdslam/synth/options.h"

namespace crowdslam::synth {

// world_from_cam of the (left / RGB) camera for each frame, stamped kFirstTimestampS + i / kFps.
io::Trajectory generate_trajectory(TrajectoryKind kind, int frames, std::uint64_t seed);

// Camera orientation looking along (yaw, pitch) in the world (z up), rolled about the view axis.
geometry::SE3 look_pose(const Eigen::Vector3d& position, double yaw, double pitch, double roll);

}  // namespace crowdslam::synth
