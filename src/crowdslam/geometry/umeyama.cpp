#include "crowdslam/geometry/umeyama.h"

#include <Eigen/SVD>
#include <cassert>

namespace crowdslam::geometry {

Similarity align_umeyama(const Eigen::Matrix3Xd& source, const Eigen::Matrix3Xd& target, bool with_scale) {
  assert(source.cols() == target.cols() && source.cols() > 0);
  const Vec3 source_mean = source.rowwise().mean();
  const Vec3 target_mean = target.rowwise().mean();
  const Eigen::Matrix3Xd source_centred = source.colwise() - source_mean;
  const Eigen::Matrix3Xd target_centred = target.colwise() - target_mean;

  // W = sum source_i * target_i^T; TUM's script takes the SVD of W^T = U d Vh and rot = U S Vh.
  const Mat3 w = source_centred * target_centred.transpose();
  Eigen::JacobiSVD<Mat3> svd(w.transpose(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Mat3 u = svd.matrixU();
  const Mat3 vh = svd.matrixV().transpose();
  Mat3 s = Mat3::Identity();
  if (u.determinant() * vh.determinant() < 0) s(2, 2) = -1;

  Similarity result;
  result.rotation = u * s * vh;
  if (with_scale) {
    const double source_variance = source_centred.squaredNorm();
    const Eigen::Vector3d d = svd.singularValues();
    const double trace_ds = d(0) * s(0, 0) + d(1) * s(1, 1) + d(2) * s(2, 2);
    result.scale = source_variance > 0 ? trace_ds / source_variance : 1.0;
  }
  result.translation = target_mean - result.scale * (result.rotation * source_mean);
  return result;
}

}  // namespace crowdslam::geometry
