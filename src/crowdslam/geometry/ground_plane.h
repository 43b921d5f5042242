#pragma once
// The ground under a camera that rides at a constant height above it (a camera fixed on a car or a ground
// robot): the one length a monocular map sees in every keyframe.
//
// A monocular map has no scale of its own; local BA passes it from keyframe to keyframe, and where the
// parallax stays small for long (a slow turn) it drifts by 15-20 % (docs/MAPPING.md, "Ground constraint"). The
// camera's height above the road does not change, so the road under each keyframe, measured in that
// keyframe's camera frame, shows the drift, and a global BA that holds it constant removes it
// (loop::GlobalBundleAdjuster with ground constraints).
//
// estimate_ground finds that road in every keyframe:
//   1. a RANSAC plane per keyframe through its points below the horizon (camera frame: x right, y down,
//      z forward; normal within max_tilt_deg of +y);
//   2. the mounting's normal: the fitted normal most others agree with (consensus_deg), averaged over
//      those that do; a rigid mount keeps it, whatever single fits picked (a car's side, a kerb);
//   3. per keyframe, the ground along that normal: the distance that most points lie at (a 1-D mode,
//      inlier_ratio of the distance), its points' plane refined by least squares (kept when within
//      max_normal_change_deg of the mounting's normal, which allows for a road's change of slope);
//   4. the reference height: the median of the keyframes' distances; keyframes further than
//      max_height_change from it (a road hidden by cars, a pavement) give no ground.
#include <cstdint>
#include <optional>
#include <vector>

#include "crowdslam/geometry/se3.h"

namespace crowdslam::geometry {

struct GroundPlaneOptions {
  double max_tilt_deg = 15.0;          // a RANSAC fit's normal against the camera's +y axis
  double inlier_ratio = 0.03;          // |normal . p - distance| < inlier_ratio * distance
  double min_below_ratio = 0.03;       // candidates: y > min_below_ratio * z (below the horizon)
  int min_inliers = 15;
  int iterations = 150;                // RANSAC hypotheses per keyframe
  double consensus_deg = 3.0;          // fits within this of the mounting's normal agree with it
  double max_normal_change_deg = 5.0;  // a keyframe's refined normal against the mounting's
  double max_lateral_ratio = 1.5;      // ground points within this many heights of the camera, sideways
  double max_height_change = 0.3;      // relative, against the reference height
  // The sigma of a keyframe's height in BA, relative to the reference height: each of its n ground points
  // gets keyframe_sigma * sqrt(n) (measured: 0.01, docs/MAPPING.md "Ground constraint").
  double keyframe_sigma = 0.01;
  void check() const;                  // throws InputError
};

struct GroundPlane {
  Vec3 normal = Vec3::UnitY();       // unit, camera frame, towards the ground
  double distance = 0.0;             // of the plane from the camera centre
  std::vector<std::size_t> inliers;  // indices into the points given
};

// RANSAC plane through camera-frame points (deterministic for a seed), refined by least squares on its
// inliers. Empty when no plane within the tilt has min_inliers.
std::optional<GroundPlane> fit_ground_plane(const std::vector<Vec3>& points_cam, const GroundPlaneOptions& options,
                                            std::uint64_t seed);

// The unit vector most of `normals` lie within max_angle_deg of (one of them, the one with most such
// neighbours), averaged over those neighbours. Empty when fewer than min_support agree.
std::optional<Vec3> consensus_normal(const std::vector<Vec3>& normals, double max_angle_deg, int min_support);

// The ground along a known normal: the distance most points below the horizon lie at (within
// inlier_ratio of it), then the least-squares plane of those points when its normal stays within
// max_normal_change_deg of `normal`. Empty with fewer than min_inliers.
std::optional<GroundPlane> ground_along_normal(const std::vector<Vec3>& points_cam, const Vec3& normal,
                                               const GroundPlaneOptions& options);

struct GroundEstimate {
  Vec3 normal = Vec3::UnitY();                    // the mounting's normal (camera frame)
  double height = 0.0;                            // the reference distance, map units
  std::vector<std::optional<GroundPlane>> planes;  // per keyframe given; empty where no ground is used
  [[nodiscard]] int keyframes_with_ground() const;
};

// Steps 1-4 above over each keyframe's points (camera frame). Empty when no consensus normal exists
// (fewer than 3 keyframes, or fewer than a fifth of the fits, agree).
std::optional<GroundEstimate> estimate_ground(const std::vector<std::vector<Vec3>>& points_per_keyframe,
                                              const GroundPlaneOptions& options);

}  // namespace crowdslam::geometry
