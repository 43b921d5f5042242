#pragma once
// Trajectories as TUM's evaluation scripts see them: read into a dict keyed by timestamp, so for a
// duplicated stamp the LAST line wins; then ordered by stamp.
#include "crowdslam/io/trajectory.h"

namespace crowdslam::eval {

io::Trajectory unique_sorted_by_stamp(const io::Trajectory& trajectory);

// The trajectory's timestamps, in its order.
std::vector<double> stamps_of(const io::Trajectory& trajectory);

}  // namespace crowdslam::eval
