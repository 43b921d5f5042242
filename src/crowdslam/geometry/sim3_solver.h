#pragma once
// RANSAC estimation of the similarity between two keyframes from 3D-3D matches (loop closing).
//
// Minimal sets of 3 matches give a model by Horn's closed form (align_umeyama; scale fixed to 1 for
// RGB-D / stereo). A match is an inlier when both reprojections fit:
//   point_in_cam2 mapped into camera 1 projects within sqrt(chi2 * sigma2_1) px of pixel1, and
//   point_in_cam1 mapped into camera 2 projects within sqrt(chi2 * sigma2_2) px of pixel2
// (and both mapped points lie in front of their camera). The best model is refit on all its inliers
// (kept if it has at least as many inliers). The number of iterations adapts to the inlier ratio
// (probability of one all-inlier sample), at most max_iterations.
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "crowdslam/geometry/camera.h"
#include "crowdslam/geometry/sim3.h"

namespace crowdslam::geometry {

// One 3D-3D correspondence between keyframe 1 and keyframe 2.
struct Sim3Match {
  Vec3 point_in_cam1 = Vec3::Zero();                 // map point in camera-1 coordinates
  Vec3 point_in_cam2 = Vec3::Zero();                 // its matched map point in camera-2 coordinates
  Eigen::Vector2d pixel1 = Eigen::Vector2d::Zero();  // undistorted keypoint in image 1
  Eigen::Vector2d pixel2 = Eigen::Vector2d::Zero();  // undistorted keypoint in image 2
  double sigma2_1 = 1.0;                             // keypoint scale variance (level sigma^2) in image 1
  double sigma2_2 = 1.0;                             // ... in image 2
};

struct Sim3SolverOptions {
  bool fix_scale = true;      // RGB-D / stereo: s = 1
  double probability = 0.99;  // of drawing at least one all-inlier sample
  int min_inliers = 20;
  int max_iterations = 300;
  double chi2 = 9.210;  // chi-square 99 %, 2 dof
  uint64_t seed = 1;

  // Throws InputError naming the bad option.
  void check() const;
};

struct Sim3Result {
  Sim3 cam1_from_cam2;
  std::vector<bool> inliers;  // per match
  int num_inliers = 0;
  int iterations = 0;  // RANSAC samples drawn
};

// std::nullopt when fewer than min_inliers matches fit the best model (or fewer than 3 matches).
// Deterministic for a given seed. Does not call options.check().
std::optional<Sim3Result> solve_sim3_ransac(const PinholeCamera& camera1, const PinholeCamera& camera2,
                                            const std::vector<Sim3Match>& matches,
                                            const Sim3SolverOptions& options = {});

// Inlier flags of a model under the reprojection test above; returns the number of inliers.
int sim3_inliers(const PinholeCamera& camera1, const PinholeCamera& camera2,
                 const std::vector<Sim3Match>& matches, const Sim3& cam1_from_cam2, double chi2,
                 std::vector<bool>& inliers);

}  // namespace crowdslam::geometry
