#pragma once
// Timestamp association exactly as TUM's associate.py / evaluate_ate.py:
// all pairs (a, b) with |a - (b + offset)| < max_difference are sorted by (difference, a, b) and taken
// greedily, each stamp used at most once; the result is sorted by a.
#include <cstddef>
#include <utility>
#include <vector>

namespace crowdslam::io {

struct Association {
  std::size_t first_index = 0;   // index into the first list
  std::size_t second_index = 0;  // index into the second list
};

// `first` and `second` need not be sorted. Duplicate stamps within one list are the caller's business
// (TUM's scripts read lists into dicts, so the last duplicate wins; see dedupe_last_wins()).
std::vector<Association> associate_timestamps(const std::vector<double>& first, const std::vector<double>& second,
                                              double max_difference = 0.02, double offset = 0.0);

// Indices of the entries kept when a list is read into a dict keyed by stamp (later duplicates replace
// earlier ones, keeping the position of the first), in ascending stamp order.
std::vector<std::size_t> dedupe_last_wins(const std::vector<double>& stamps);

}  // namespace crowdslam::io
