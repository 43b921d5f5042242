#pragma once
// Levenberg-Marquardt for pose-point reprojection problems with the point blocks eliminated by the
// Schur complement: crowdslam's own solver for local bundle adjustment (bundle_adjustment.h,
// BaLinearSolver::kOwnSchur).
//
// Why not Ceres here: a local window mixes mono (2-row) and stereo / RGB-D (3-row) residuals, so Ceres'
// Schur eliminator runs its fully dynamic <-1, -1, -1> instance, and profiling showed its chunk outer
// products at a quarter of a local BA's time (bench_optim's 20-keyframe window). The structure is fixed
// here (6-dof poses, 3-dof points), so every block product has static sizes, and the reduced camera
// system of a local window (at most a few dozen free poses) is small enough for a dense Cholesky.
//
// The problem and the schedule are the same as with Ceres:
//   cost = 1/2 sum rho(|r_i|^2), r_i = sqrt(inv_sigma2) * (projection - observation) (2 or 3 rows),
//   or, for a plane constraint, sqrt_information * (normal . p_cam - distance) (1 row),
//   rho = Huber with delta^2 = the chi2 threshold (robust pass) or identity;
//   poses are cam_from_world, updated by left perturbation (optim::left_update), points by addition;
//   LM with Marquardt's diagonal scaling (H + mu diag(H), diag clamped to [1e-6, 1e32]), Nielsen's
//   damping update, Ceres' defaults for the initial mu (1e-4), the minimum relative decrease (1e-3),
//   the function tolerance (1e-6) and the parameter tolerance (1e-8).
// Robust residuals are weighted by rho'(s) (iteratively reweighted least squares). A step that puts an
// observed point at |z| < 1e-12 in front of its camera is rejected, as Ceres rejects a failed cost.
#include <atomic>
#include <vector>

#include "crowdslam/geometry/camera.h"
#include "crowdslam/geometry/se3.h"

namespace crowdslam::optim {

struct SchurObservation {
  int pose = -1;   // index into poses
  int point = -1;  // index into points
  geometry::Vec2 pixel = geometry::Vec2::Zero();
  double right_u = -1.0;  // used when stereo
  double sqrt_information = 1.0;
  bool stereo = false;
  double huber_delta = 0.0;  // 0: no robust loss
  // A plane constraint instead of a reprojection: residual sqrt_information * (normal . p_cam - distance)
  // (one row; pixel, right_u and stereo unused).
  bool plane = false;
  geometry::Vec3 normal = geometry::Vec3::Zero();
  double distance = 0.0;
};

// A measured relative pose between two poses: residual e = (translation, so3 log of the rotation) of
// poses[a] * poses[b]^-1 * a_from_b^-1, cost 1/2 e^T diag(weight) e (never robust). Jacobians: I for pose
// a and -Ad(poses[a] * poses[b]^-1) for pose b, in the update's (rho, phi) coordinates, exact at e = 0.
struct SchurRelativePose {
  int pose_a = -1;
  int pose_b = -1;
  geometry::SE3 a_from_b;
  geometry::Vec6 weight = geometry::Vec6::Zero();  // 1 / sigma^2: translation x3, rotation x3
};

struct SchurLmSummary {
  double initial_cost = 0.0;
  double final_cost = 0.0;
  int successful_steps = 0;
  int unsuccessful_steps = 0;
  bool valid = true;  // false: the initial state could not be evaluated (nothing changed)
};

// Minimises the cost over the poses not marked fixed and over every point with an observation.
// Stops after max_iterations linear solves (successful or not), at convergence, or after the iteration
// on which *abort_flag becomes true; the state always holds the last accepted iterate.
SchurLmSummary solve_schur_lm(const geometry::PinholeCamera& camera, std::vector<geometry::SE3>& poses,
                              const std::vector<bool>& fixed, std::vector<geometry::Vec3>& points,
                              const std::vector<SchurObservation>& observations, int max_iterations,
                              const std::atomic<bool>* abort_flag = nullptr,
                              const std::vector<SchurRelativePose>& relative_poses = {});

}  // namespace crowdslam::optim
