#include "crowdslam/io/associate.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

namespace crowdslam::io {

std::vector<Association> associate_timestamps(const std::vector<double>& first, const std::vector<double>& second,
                                              double max_difference, double offset) {
  // Candidate pairs within the window. Both lists are sorted first so the window search is
  // O((n + m) log m + candidates) instead of the script's O(n m); the chosen pairs are identical.
  std::vector<size_t> second_order(second.size());
  for (size_t i = 0; i < second.size(); ++i) second_order[i] = i;
  std::sort(second_order.begin(), second_order.end(), [&](size_t a, size_t b) { return second[a] < second[b]; });
  std::vector<double> second_shifted(second.size());
  for (size_t k = 0; k < second_order.size(); ++k) second_shifted[k] = second[second_order[k]] + offset;

  struct Candidate {
    double difference;
    double a;
    double b;
    size_t first_index;
    size_t second_index;
  };
  std::vector<Candidate> candidates;
  for (size_t i = 0; i < first.size(); ++i) {
    const double a = first[i];
    if (!std::isfinite(a)) continue;
    auto it = std::lower_bound(second_shifted.begin(), second_shifted.end(), a - max_difference);
    for (; it != second_shifted.end() && *it <= a + max_difference; ++it) {
      const size_t k = static_cast<size_t>(it - second_shifted.begin());
      const size_t j = second_order[k];
      const double difference = std::abs(a - (second[j] + offset));
      if (difference < max_difference) candidates.push_back({difference, a, second[j], i, j});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
    return std::tie(x.difference, x.a, x.b, x.first_index, x.second_index) <
           std::tie(y.difference, y.a, y.b, y.first_index, y.second_index);
  });
  std::vector<bool> first_used(first.size(), false);
  std::vector<bool> second_used(second.size(), false);
  std::vector<Association> matches;
  for (const auto& c : candidates) {
    if (first_used[c.first_index] || second_used[c.second_index]) continue;
    first_used[c.first_index] = true;
    second_used[c.second_index] = true;
    matches.push_back({c.first_index, c.second_index});
  }
  std::sort(matches.begin(), matches.end(), [&](const Association& x, const Association& y) {
    return std::tie(first[x.first_index], second[x.second_index]) < std::tie(first[y.first_index], second[y.second_index]);
  });
  return matches;
}

std::vector<size_t> dedupe_last_wins(const std::vector<double>& stamps) {
  std::map<double, size_t> last;
  for (size_t i = 0; i < stamps.size(); ++i) last[stamps[i]] = i;
  std::vector<size_t> kept;
  kept.reserve(last.size());
  for (const auto& [stamp, index] : last) kept.push_back(index);
  return kept;
}

}  // namespace crowdslam::io
