#include "crowdslam/bow/bow_vector.h"

#include <algorithm>
#include <cmath>

namespace crowdslam::bow {

void normalize_l1(BowVector& bow) {
  double sum = 0.0;
  for (const auto& [word, weight] : bow) sum += std::abs(weight);
  if (sum <= 0.0) return;
  for (auto& [word, weight] : bow) weight /= sum;
}

double l1_score(const BowVector& a, const BowVector& b) {
  if (a.empty() || b.empty()) return 0.0;
  // sum |a_i - b_i| over the union of words, by a merge of the two sorted maps.
  double distance = 0.0;
  auto ia = a.begin();
  auto ib = b.begin();
  while (ia != a.end() || ib != b.end()) {
    if (ib == b.end() || (ia != a.end() && ia->first < ib->first)) {
      distance += std::abs(ia->second);
      ++ia;
    } else if (ia == a.end() || ib->first < ia->first) {
      distance += std::abs(ib->second);
      ++ib;
    } else {
      distance += std::abs(ia->second - ib->second);
      ++ia;
      ++ib;
    }
  }
  return std::clamp(1.0 - 0.5 * distance, 0.0, 1.0);
}

}  // namespace crowdslam::bow
