#include "crowdslam/io/dataset_ground_truth.h"

#include <filesystem>

#include "crowdslam/util/error.h"

namespace crowdslam::io {
namespace {

void require_file(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw input_error(path, "ground-truth file does not exist");
}

}  // namespace

Trajectory load_tum_ground_truth(const std::string& path) {
  require_file(path);
  return read_tum_trajectory(path);
}

Trajectory load_kitti_ground_truth(const std::string& path, const std::vector<double>& stamps) {
  require_file(path);
  return read_kitti_trajectory(path, stamps);
}

Trajectory load_euroc_ground_truth(const std::string& path) {
  require_file(path);
  return read_euroc_trajectory(path);
}

}  // namespace crowdslam::io
