#pragma once
// Rotation consistency check of ORB-SLAM: the angle difference between matched keypoints is
// histogrammed in 30 bins; matches outside the three most populated bins are rejected (a second or third
// bin is kept only if it holds at least 10% of the first's count).
#include <array>
#include <cstddef>
#include <vector>

namespace crowdslam::match {

class RotationHistogram {
 public:
  static constexpr int kBins = 30;
  // angle_delta_deg = angle in the first image - angle in the second.
  void add(float angle_delta_deg, std::size_t match_id);
  // Ids of matches that fail the check.
  [[nodiscard]] std::vector<std::size_t> rejected() const;

 private:
  std::array<std::vector<std::size_t>, kBins> bins_;
};

}  // namespace crowdslam::match
