#include "crowdslam/match/rotation_histogram.h"

#include <cmath>

namespace crowdslam::match {

void RotationHistogram::add(float angle_delta_deg, size_t match_id) {
  float delta = std::fmod(angle_delta_deg, 360.0f);
  if (delta < 0.0f) delta += 360.0f;
  int bin = static_cast<int>(std::lround(delta * kBins / 360.0f));
  if (bin == kBins) bin = 0;
  bins_[static_cast<size_t>(bin)].push_back(match_id);
}

std::vector<size_t> RotationHistogram::rejected() const {
  // The three most populated bins.
  int first = -1, second = -1, third = -1;
  size_t n1 = 0, n2 = 0, n3 = 0;
  for (int i = 0; i < kBins; ++i) {
    const size_t n = bins_[static_cast<size_t>(i)].size();
    if (n > n1) {
      third = second, n3 = n2;
      second = first, n2 = n1;
      first = i, n1 = n;
    } else if (n > n2) {
      third = second, n3 = n2;
      second = i, n2 = n;
    } else if (n > n3) {
      third = i, n3 = n;
    }
  }
  if (n2 < 0.1 * n1) second = -1;
  if (n3 < 0.1 * n1) third = -1;
  std::vector<size_t> result;
  for (int i = 0; i < kBins; ++i) {
    if (i == first || i == second || i == third) continue;
    result.insert(result.end(), bins_[static_cast<size_t>(i)].begin(), bins_[static_cast<size_t>(i)].end());
  }
  return result;
}

}  // namespace crowdslam::match
