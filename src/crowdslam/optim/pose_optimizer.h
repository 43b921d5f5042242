#pragma once
// Motion-only pose optimisation (tracking): refines one camera pose against fixed 3D points.
//
// Our own small Levenberg-Marquardt on Eigen (no Ceres: its per-call setup costs more than the
// whole solve at tracking rates). Pose update by left perturbation, cam_from_world <- exp(d) *
// cam_from_world with d = (rho, phi), translation part first (see se3_update.h).
//
// Schedule (ORB-SLAM2 style): `rounds` rounds of `iterations_per_round` LM iterations. After each
// round every observation (including current outliers) is classified by its chi2 at the current
// pose: chi2 > chi2_mono (2 dof) / chi2_stereo (3 dof) or point behind the camera -> outlier.
// The next round uses only inliers, so an outlier can come back. The Huber kernel (delta =
// sqrt(chi2 threshold)) is used in the first `robust_rounds` rounds and dropped afterwards.
// Each round continues from the previous round's pose (ORB-SLAM2 restarts every round from the
// initial pose; warm starting converges at least as well).
#include <vector>

#include "crowdslam/geometry/camera.h"
#include "crowdslam/geometry/se3.h"

namespace crowdslam::optim {

struct PoseObservation {
  geometry::Vec3 point_world;
  geometry::Vec2 pixel;     // undistorted keypoint
  double right_u = -1.0;    // right-image u (stereo / RGB-D virtual stereo); < 0 = mono observation
  double inv_sigma2 = 1.0;  // 1 / sigma^2 of the keypoint's pyramid level (information = inv_sigma2 * I)

  [[nodiscard]] bool is_stereo() const { return right_u >= 0.0; }
};

struct PoseOptimizerOptions {
  int rounds = 4;
  int iterations_per_round = 10;
  int robust_rounds = 2;  // rounds [0, robust_rounds) use the Huber kernel
  double chi2_mono = 5.991;
  double chi2_stereo = 7.815;
  int min_observations = 3;  // fewer observations: no optimisation, success = false

  // Throws InputError naming the bad option. Not called by optimize_pose (hot path): validate once.
  void check() const;
};

struct PoseOptimizationResult {
  bool success = false;  // false: too few observations or a non-finite pose; pose = initial
  geometry::SE3 cam_from_world;
  std::vector<bool> inliers;  // one flag per input observation
  int num_inliers = 0;
  int iterations = 0;  // LM iterations run (accepted or rejected steps)
};

// Stereo observations (right_u >= 0) need camera.bf > 0; with bf = 0 they are used as mono.
PoseOptimizationResult optimize_pose(const geometry::PinholeCamera& camera, const geometry::SE3& initial_cam_from_world,
                                     const std::vector<PoseObservation>& observations,
                                     const PoseOptimizerOptions& options = {});

}  // namespace crowdslam::optim
