#pragma once
// Relative pose error exactly as TUM's evaluate_rpe.py with --fixed_delta:
//  - both trajectories as dicts keyed by stamp (the last duplicate wins), stamps sorted;
//  - overlap check: fewer than 2 distinct estimate stamps that map to a ground-truth stamp and back
//    (find_closest_index both ways) -> error;
//  - pairs (i, j) with j = find_closest_index(index, index[i] + delta), index = estimate stamps (unit
//    seconds) or 0..n-1 (unit frames); pairs whose j is the LAST index are dropped (script quirk, kept);
//  - ground-truth poses: closest stamp to est stamp + offset, pair skipped if either is further than
//    2 * median(ground-truth stamp interval);
//  - error = inv(scale(inv(E_j) E_i)) * (inv(G_j) G_i), translation norm and rotation angle.
// Deviations: the script samples 10000 random pairs when there are more; we use all pairs. The script
// skips lines with zero quaternions or NaNs; our readers reject such files (InputError naming the line).
#include <cstddef>
#include <string>
#include <vector>

#include "crowdslam/eval/error_stats.h"
#include "crowdslam/io/trajectory.h"

namespace crowdslam::eval {

enum class DeltaUnit { kSeconds, kFrames };
// "s", "frames" (also "f"); parse throws InputError naming the value.
const char* to_string(DeltaUnit unit);
DeltaUnit parse_delta_unit(const std::string& text);

struct RpeOptions {
  double delta = 1.0;  // in delta_unit
  DeltaUnit delta_unit = DeltaUnit::kSeconds;
  double offset_s = 0.0;  // added to the estimate's stamps
  double scale = 1.0;     // multiplies the estimate's relative translations
  void check() const;     // throws InputError naming the bad option
};

struct RpePair {
  double estimate_stamp_0 = 0.0;
  double estimate_stamp_1 = 0.0;
  double ground_truth_stamp_0 = 0.0;
  double ground_truth_stamp_1 = 0.0;
  double translation_error_m = 0.0;
  double rotation_error_rad = 0.0;
};

struct RpeResult {
  std::vector<RpePair> pairs;
  ErrorStats translation_error_m;
  ErrorStats rotation_error_deg;
  double ground_truth_max_time_difference_s = 0.0;  // 2 * median ground-truth stamp interval
};

// The script's find_closest_index (binary search; ties keep the first index probed). `sorted` not empty.
std::size_t find_closest_index(const std::vector<double>& sorted, double value);

// `ground_truth_name` / `estimate_name` (usually the file paths) are used in error messages.
RpeResult evaluate_rpe(const io::Trajectory& ground_truth, const io::Trajectory& estimate,
                       const RpeOptions& options, const std::string& ground_truth_name = "ground truth",
                       const std::string& estimate_name = "estimate");

}  // namespace crowdslam::eval
