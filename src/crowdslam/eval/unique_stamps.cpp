#include "crowdslam/eval/unique_stamps.h"

#include "crowdslam/io/associate.h"

namespace crowdslam::eval {

std::vector<double> stamps_of(const io::Trajectory& trajectory) {
  std::vector<double> stamps;
  stamps.reserve(trajectory.size());
  for (const io::StampedPose& pose : trajectory) stamps.push_back(pose.timestamp_s);
  return stamps;
}

io::Trajectory unique_sorted_by_stamp(const io::Trajectory& trajectory) {
  io::Trajectory result;
  for (std::size_t index : io::dedupe_last_wins(stamps_of(trajectory))) result.push_back(trajectory[index]);
  return result;
}

}  // namespace crowdslam::eval
