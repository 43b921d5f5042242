#pragma once
// Refinement of the similarity between two keyframes from 3D-3D matches (loop closing), on plain data.
//
// Minimises, over cam1_from_cam2 only (points fixed), for every used match
//   |project1(S12 * point_in_cam2) - pixel1|^2 / sigma2_1 + |project2(S12^-1 * point_in_cam1) - pixel2|^2 /
//   sigma2_2
// with a Huber loss per term (delta^2 = chi2). Schedule: pass 1 (iterations_first) on the used matches;
// a match is an outlier when either term exceeds chi2 or a mapped point is not in front of its camera;
// pass 2 (iterations_second) on the remaining ones; final classification of every used match -> inliers.
// Parameters: Eigen quaternion (EigenQuaternionManifold), translation, log scale (constant with fix_scale).
#include <vector>

#include "crowdslam/geometry/camera.h"
#include "crowdslam/geometry/sim3.h"
#include "crowdslam/geometry/sim3_solver.h"

namespace crowdslam::optim {

struct Sim3OptimizationOptions {
  bool fix_scale = true;  // RGB-D / stereo: the scale stays at the initial one (1)
  double chi2 = 10.0;     // outlier threshold per term; Huber delta sqrt(chi2)
  int iterations_first = 5;
  int iterations_second = 5;  // 0 disables pass 2

  // Throws InputError naming the bad option. Not called by optimize_sim3.
  void check() const;
};

struct Sim3OptimizationResult {
  geometry::Sim3 cam1_from_cam2;
  std::vector<bool> inliers;  // per match; false for matches not used
  int num_inliers = 0;
};

// `use` (same size as matches) marks the matches to optimise over (e.g. the RANSAC inliers).
Sim3OptimizationResult optimize_sim3(const geometry::PinholeCamera& camera1,
                                     const geometry::PinholeCamera& camera2,
                                     const std::vector<geometry::Sim3Match>& matches,
                                     const std::vector<bool>& use,
                                     const geometry::Sim3& initial_cam1_from_cam2,
                                     const Sim3OptimizationOptions& options = {});

}  // namespace crowdslam::optim
