#pragma once
// How far the frames bridged while people hid the view drifted (TrackerOptions::bridge_max_s): their
// positions against the ground truth under the alignment of their map segment's ATE (fitted to the
// tracked frames only), and per bridge (a run of bridged frames) the error of the last tracked frame
// before it, the largest error in it and the error of the first tracked frame after it.
#include <nlohmann/json.hpp>

#include "crowdslam/eval/ate.h"
#include "crowdslam/io/trajectory.h"

namespace crowdslam::run {

// `tracked` is the segment's camera trajectory, `bridged` its bridged frames, `ate` the segment's ATE
// (its alignment is applied to both). Null when nothing was bridged. At most `max_bridges` bridges are
// listed one by one; the totals cover them all.
nlohmann::json bridge_accuracy(const io::Trajectory& ground_truth, const io::Trajectory& tracked,
                               const io::Trajectory& bridged, const eval::AteResult& ate,
                               double max_difference_s, size_t max_bridges = 50);

}  // namespace crowdslam::run
