#pragma once
// Least-squares alignment of two point sets (Horn 1987 / Umeyama 1991).
#include <Eigen/Core>

#include "crowdslam/geometry/se3.h"

namespace crowdslam::geometry {

struct Similarity {
  Mat3 rotation = Mat3::Identity();
  Vec3 translation = Vec3::Zero();
  double scale = 1.0;
  [[nodiscard]] Vec3 apply(const Vec3& p) const { return scale * (rotation * p) + translation; }
};

// Finds the transform T minimising sum |target_i - T(source_i)|^2. Columns are points (3xN, N >= 3
// for a unique answer). With `with_scale` false the scale is fixed at 1 (SE3 alignment); the rotation
// is computed exactly as TUM's evaluate_ate.py (SVD of the cross-covariance, det sign correction).
Similarity align_umeyama(const Eigen::Matrix3Xd& source, const Eigen::Matrix3Xd& target, bool with_scale);

}  // namespace crowdslam::geometry
