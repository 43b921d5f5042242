#pragma once
// Two-view geometry for monocular initialisation (the method of the ORB-SLAM paper, our own code).
//
// 1. Models: a homography H21 (x2 ~ H21 x1, planar scene or pure rotation) and a fundamental matrix F21
//    (x2^T F21 x1 = 0, general scene) are estimated by RANSAC from the SAME random 8-point sets
//    (normalised DLT for H, normalised 8-point with rank-2 enforcement for F).
// 2. Scoring: symmetric transfer error in both images, in units of sigma^2. A correspondence is an
//    inlier of H when both chi2 <= 5.991 (2 DoF) and of F when both point-to-epipolar-line chi2 <= 3.841
//    (1 DoF); each direction within its threshold adds 5.991 - chi2 to the model's score, so both models
//    score the same for the same error.
// 3. Selection: R_H = S_H / (S_H + S_F) > 0.45 selects the homography, else the fundamental matrix.
// 4. Reconstruction: the selected model gives relative pose hypotheses (4 from H by
//    cv::decomposeHomographyMat, 4 from E = K^T F K). Each hypothesis triangulates the model's inliers;
//    a point is good when it is in front of both cameras (or has no parallax to speak of) and reprojects
//    within 2 sigma in both images. The hypothesis with the most good points wins if it is a clear
//    winner (no other has more than clear_winner_ratio of its count), its good points are at least
//    max(min_good_fraction * inliers, min_triangulated), and the parallax of its 50th-best point
//    exceeds min_parallax_deg. Pure rotations and too-small baselines therefore fail.
// 5. With a prior (TwoViewPrior: the relative pose a motion model predicts, as when a monocular map is
//    re-anchored), only hypotheses that agree with it take part in step 4, and when the selected model
//    has none, the other model's hypotheses are tried. A plane seen from two views has two
//    decompositions that explain every point (the two-fold ambiguity of a homography); they differ in
//    rotation and in the direction of travel, and the prior tells them apart where step 4 alone rejects
//    the pair as ambiguous.
#include <cstdint>
#include <optional>
#include <vector>

#include "crowdslam/geometry/camera.h"
#include "crowdslam/geometry/se3.h"

namespace crowdslam::geometry {

enum class TwoViewModel { kHomography, kFundamental };
const char* to_string(TwoViewModel model);

inline constexpr double kChi2OneDof = 3.841;  // 95 % quantile, 1 DoF (point-to-line distance)

struct TwoViewOptions {
  double sigma_px = 1.0;  // keypoint position standard deviation (pixels)
  int ransac_iterations = 200;
  double homography_ratio_threshold = 0.45;  // R_H above this selects the homography
  double min_parallax_deg = 1.0;
  int min_triangulated = 50;       // good points a reconstruction needs at least
  double min_good_fraction = 0.9;  // ... and at least this fraction of the model's inliers
  double clear_winner_ratio =
      0.7;                 // a second hypothesis with more than this fraction of good points: ambiguous
  std::uint64_t seed = 0;  // RANSAC sample sets (deterministic)
  void check() const;      // throws InputError naming the bad option
};

// Normalised DLT homography (Hartley normalisation) from >= 4 correspondences: x2 ~ H21 x1, ||H||_F = 1.
Mat3 homography_dlt(const std::vector<Vec2>& points1, const std::vector<Vec2>& points2);
// Normalised 8-point fundamental matrix from >= 8 correspondences: x2^T F21 x1 = 0, rank 2, ||F||_F = 1.
Mat3 fundamental_eight_point(const std::vector<Vec2>& points1, const std::vector<Vec2>& points2);

struct ModelScore {
  double score = 0.0;
  int num_inliers = 0;
  std::vector<bool> inliers;
};
ModelScore score_homography(const Mat3& homography_21, const std::vector<Vec2>& points1,
                            const std::vector<Vec2>& points2, double sigma_px);
ModelScore score_fundamental(const Mat3& fundamental_21, const std::vector<Vec2>& points1,
                             const std::vector<Vec2>& points2, double sigma_px);

// The relative pose another source predicts (step 5). A hypothesis agrees when its rotation is within
// max_rotation_deg + rotation_share * (the prior's rotation angle) of the prior's, and, when
// check_direction, its direction of travel within max_direction_deg of the prior's.
struct TwoViewPrior {
  SE3 cam2_from_cam1;
  bool check_direction = true;  // false when the prior's translation is too short to have a direction
  double max_rotation_deg = 2.0;
  double rotation_share = 0.5;
  double max_direction_deg = 45.0;
};
bool agrees_with_prior(const SE3& cam2_from_cam1, const TwoViewPrior& prior);

struct TwoViewModels {
  Mat3 homography_21 = Mat3::Zero();
  ModelScore homography;
  Mat3 fundamental_21 = Mat3::Zero();
  ModelScore fundamental;
  double homography_ratio = 0.0;  // R_H = S_H / (S_H + S_F)
  TwoViewModel selected = TwoViewModel::kFundamental;
};
// Both models by RANSAC on the same 8-point sets, each refined on its inliers, and the selection.
// Needs >= 8 correspondences (pixels, undistorted).
TwoViewModels estimate_two_view_models(const std::vector<Vec2>& points1, const std::vector<Vec2>& points2,
                                       const TwoViewOptions& options);

// The four cam2_from_cam1 hypotheses of an essential matrix (unit translation).
std::vector<SE3> poses_from_essential(const Mat3& essential);
// The hypotheses of a homography between two views of camera K (cv::decomposeHomographyMat; translation
// scaled to unit length; hypotheses without translation are kept with t = 0).
std::vector<SE3> poses_from_homography(const Mat3& homography_21, const Mat3& intrinsics);

// Triangulation of correspondences under one hypothesis.
struct PoseCheck {
  int num_good = 0;                // consistent points (see the header comment)
  std::vector<Vec3> points_cam1;   // per correspondence, valid where triangulated[i]
  std::vector<bool> triangulated;  // good, in front of both cameras and parallax above ~0.36 degrees
  double parallax_deg = 0.0;       // of the 50th-best good point (or the worst, if fewer)
};
PoseCheck check_relative_pose(const SE3& cam2_from_cam1, const PinholeCamera& camera,
                              const std::vector<Vec2>& points1, const std::vector<Vec2>& points2,
                              const std::vector<bool>& use, double sigma_px);

struct TwoViewReconstruction {
  TwoViewModel model = TwoViewModel::kFundamental;
  SE3 cam2_from_cam1;             // unit baseline
  std::vector<Vec3> points_cam1;  // per correspondence, valid where triangulated[i]
  std::vector<bool> triangulated;
  int num_triangulated = 0;
  double parallax_deg = 0.0;
};

// Picks the winning hypothesis among `candidates` (see the header comment; with `prior`, among those that
// agree with it), or nullopt.
std::optional<TwoViewReconstruction> choose_hypothesis(
    const std::vector<SE3>& candidates, const PinholeCamera& camera, const std::vector<Vec2>& points1,
    const std::vector<Vec2>& points2, const ModelScore& model, const TwoViewOptions& options,
    const TwoViewPrior* prior = nullptr);

// The whole pipeline: models, selection, reconstruction. `models` (optional) receives the estimates.
std::optional<TwoViewReconstruction> reconstruct_two_view(const PinholeCamera& camera,
                                                          const std::vector<Vec2>& points1,
                                                          const std::vector<Vec2>& points2,
                                                          const TwoViewOptions& options,
                                                          TwoViewModels* models = nullptr,
                                                          const TwoViewPrior* prior = nullptr);

}  // namespace crowdslam::geometry
