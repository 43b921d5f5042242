#pragma once
// Local bundle adjustment (local mapping) with our Schur LM (schur_lm.h) or Ceres on plain data: keyframe
// poses (cam_from_world, Se3Manifold) and 3D points. Independent of the map module: the mapper copies its
// local window into these structs and writes the result back.
//
// Schedule (ORB-SLAM2 style):
//   pass 1: all observations, Huber loss (delta^2 = chi2 threshold), first_pass_iterations;
//   classify: chi2 > chi2_mono / chi2_stereo, or point not in front of the camera -> outlier;
//   pass 2: inliers only, no robust loss, second_pass_iterations (skipped if aborted);
//   final classification of every observation -> `outliers` (the mapper erases those).
// Abort: when *abort_flag becomes true the running pass stops after its current iteration,
// keeping the last accepted state (ceres::SOLVER_TERMINATE_SUCCESSFULLY), and pass 2 is skipped.
// If the flag is already set on entry nothing is optimised and the input is returned unchanged.
#include <atomic>
#include <cstddef>
#include <vector>

#include "crowdslam/geometry/camera.h"
#include "crowdslam/geometry/se3.h"

namespace crowdslam::optim {

struct BaKeyframe {
  int id = -1;
  geometry::SE3 cam_from_world;
  bool fixed = false;  // covisible keyframes outside the local window (and the gauge keyframe)
};

struct BaPoint {
  int id = -1;
  geometry::Vec3 world = geometry::Vec3::Zero();
};

struct BaObservation {
  int keyframe_id = -1;
  int point_id = -1;
  geometry::Vec2 pixel = geometry::Vec2::Zero();  // undistorted keypoint
  double right_u = -1.0;                          // < 0: mono observation
  double inv_sigma2 = 1.0;                        // 1 / sigma^2 of the keypoint's pyramid level

  [[nodiscard]] bool is_stereo() const { return right_u >= 0.0; }
};

// A point known to lie on a plane seen from a keyframe (the ground under a vehicle's camera:
// mapping/ground_plane.h): residual (normal_cam . (cam_from_world * point) - distance) / sigma, Huber loss
// with delta 1 in both passes. Never an outlier and never erased; unknown ids are skipped.
struct BaPlaneConstraint {
  int keyframe_id = -1;
  int point_id = -1;
  geometry::Vec3 normal_cam = geometry::Vec3::UnitY();  // unit normal in the keyframe's camera frame
  double distance = 0.0;  // of the plane from the camera centre, map units
  double sigma = 1.0;     // map units
};

// A measured relative pose between two keyframes: keyframe_id's cam_from_world times other_id's
// world_from_cam should be `cam_from_other`; residual relative_pose_error (se3_update.h) weighed by
// 1 / sigma^2 (translation: map units; rotation: radians), no robust loss, never an outlier. Tracking
// measures it when it makes a keyframe (LocalMapperOptions::odometry_sigma_deg). Skipped when either id
// is unknown or both keyframes are fixed.
struct BaRelativePose {
  int keyframe_id = -1;
  int other_id = -1;
  geometry::SE3 cam_from_other;
  double translation_sigma = 1.0;
  double rotation_sigma_rad = 1.0;
};

enum class BaLinearSolver {
  kAuto,         // kOwnSchur up to kOwnSchurMaxFreePoses free poses (local windows), else Ceres kSparseSchur
  kSparseSchur,  // Ceres SPARSE_SCHUR; falls back to DENSE_SCHUR when no sparse backend is compiled in
  kDenseSchur,   // Ceres DENSE_SCHUR
  kOwnSchur,     // optim::solve_schur_lm (schur_lm.h): the same problem, static block sizes, dense Cholesky
};

// kAuto's limit for kOwnSchur: its reduced camera system is dense (6 x free poses squared).
constexpr int kOwnSchurMaxFreePoses = 64;

struct BundleAdjustmentOptions {
  int first_pass_iterations = 5;
  int second_pass_iterations = 10;  // 0 disables the second pass
  double chi2_mono = 5.991;
  double chi2_stereo = 7.815;
  int num_threads = 1;
  BaLinearSolver linear_solver = BaLinearSolver::kAuto;

  // Throws InputError naming the bad option. Not called by local_bundle_adjustment: validate once.
  void check() const;
};

struct BundleAdjustmentResult {
  std::vector<BaKeyframe> keyframes;  // input order; fixed ones unchanged
  std::vector<BaPoint> points;        // input order
  std::vector<std::size_t> outliers;  // indices into the input observations, ascending
  bool aborted = false;
  int iterations = 0;  // solver iterations (linear solves) over both passes
  double initial_cost = 0.0;
  double final_cost = 0.0;  // of the last pass run (robust cost if pass 2 did not run)
};

// Observations must reference ids present in `keyframes` / `points` (unknown ids are skipped).
// Stereo observations need camera.bf > 0; with bf = 0 they are used as mono.
BundleAdjustmentResult local_bundle_adjustment(const geometry::PinholeCamera& camera,
                                               const std::vector<BaKeyframe>& keyframes,
                                               const std::vector<BaPoint>& points,
                                               const std::vector<BaObservation>& observations,
                                               const BundleAdjustmentOptions& options = {},
                                               const std::atomic<bool>* abort_flag = nullptr,
                                               const std::vector<BaPlaneConstraint>& planes = {},
                                               const std::vector<BaRelativePose>& relative_poses = {});

// Whether this Ceres build has a sparse linear algebra backend (SuiteSparse, CXSparse, Eigen...).
bool ceres_has_sparse_backend();

}  // namespace crowdslam::optim
