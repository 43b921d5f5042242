#pragma once
// Absolute trajectory error exactly as TUM's evaluate_ate.py:
//  1. both trajectories as dicts keyed by stamp (the last duplicate wins), ordered by stamp;
//  2. matches = associate(gt stamps, est stamps, offset, max_difference) (io/associate.h);
//  3. model = estimate positions * scale, data = ground-truth positions of the matches;
//  4. model aligned onto data (SE3 as the script's align(), Sim3 = Umeyama with scale, or none);
//  5. errors e_i = |s R model_i + t - data_i| and their statistics.
// Deviation: the script needs 2 matches, we need 3 (a rotation from 2 points is not unique).
#include <cstddef>
#include <string>
#include <vector>

#include "crowdslam/eval/error_stats.h"
#include "crowdslam/geometry/umeyama.h"
#include "crowdslam/io/associate.h"
#include "crowdslam/io/trajectory.h"

namespace crowdslam::eval {

enum class Alignment { kSe3, kSim3, kNone };
// "se3", "sim3", "none"; parse throws InputError naming the value.
const char* to_string(Alignment alignment);
Alignment parse_alignment(const std::string& text);

struct AteOptions {
  Alignment alignment = Alignment::kSe3;
  double max_difference_s = 0.02;  // association window (strict <)
  double offset_s = 0.0;           // added to the estimate's stamps
  double scale = 1.0;              // multiplies the estimate's positions before alignment
  void check() const;              // throws InputError naming the bad option
};

struct AteResult {
  ErrorStats translation_error_m;
  // gt_point = alignment.apply(scale * est_point); identity for Alignment::kNone.
  geometry::Similarity alignment;
  // Into the de-duplicated, stamp-ordered trajectories (first = ground truth, second = estimate).
  std::vector<io::Association> matches;
  std::vector<double> errors_m;        // per match, same order
  std::size_t ground_truth_poses = 0;  // after de-duplication
  std::size_t estimate_poses = 0;
};

// `ground_truth_name` / `estimate_name` (usually the file paths) are used in error messages.
AteResult evaluate_ate(const io::Trajectory& ground_truth, const io::Trajectory& estimate,
                       const AteOptions& options, const std::string& ground_truth_name = "ground truth",
                       const std::string& estimate_name = "estimate");

// The estimate mapped into the ground-truth frame: positions p -> s R (scale p) + t, orientations
// rotated by R. Stamps unchanged.
io::Trajectory apply_alignment(const io::Trajectory& estimate, const geometry::Similarity& alignment,
                               double scale);

}  // namespace crowdslam::eval
