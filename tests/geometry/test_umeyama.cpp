#include <gtest/gtest.h>

#include <random>

#include "crowdslam/geometry/umeyama.h"

using namespace crowdslam::geometry;

namespace {
Eigen::Matrix3Xd random_points(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-2, 2);
  Eigen::Matrix3Xd p(3, n);
  for (int i = 0; i < n; ++i) p.col(i) = Vec3(u(rng), u(rng), u(rng));
  return p;
}
}  // namespace

TEST(Umeyama, RecoversRigidTransformExactly) {
  const auto src = random_points(50, 1);
  Vec6 twist;
  twist << 0.5, -1, 2, 0.3, -0.2, 1.2;
  const SE3 t = SE3::exp(twist);
  Eigen::Matrix3Xd dst(3, src.cols());
  for (int i = 0; i < src.cols(); ++i) dst.col(i) = t * Vec3(src.col(i));
  const Similarity s = align_umeyama(src, dst, false);
  EXPECT_LT((s.rotation - t.rotation_matrix()).norm(), 1e-10);
  EXPECT_LT((s.translation - t.translation()).norm(), 1e-10);
  EXPECT_DOUBLE_EQ(s.scale, 1.0);
}

TEST(Umeyama, RecoversScale) {
  const auto src = random_points(30, 2);
  Vec6 twist;
  twist << 0.1, 0.2, 0.3, -1.0, 0.4, 0.2;
  const SE3 t = SE3::exp(twist);
  Eigen::Matrix3Xd dst(3, src.cols());
  for (int i = 0; i < src.cols(); ++i) dst.col(i) = 2.5 * (t.rotation_matrix() * src.col(i)) + t.translation();
  const Similarity s = align_umeyama(src, dst, true);
  EXPECT_NEAR(s.scale, 2.5, 1e-10);
  EXPECT_LT((s.rotation - t.rotation_matrix()).norm(), 1e-10);
  EXPECT_LT((s.translation - t.translation()).norm(), 1e-9);
}

TEST(Umeyama, ReflectionIsNeverReturned) {
  // Planar points mirrored: the best proper rotation must have det +1.
  Eigen::Matrix3Xd src(3, 4), dst(3, 4);
  src << 1, -1, 0, 0, 0, 0, 1, -1, 0, 0, 0, 0;
  dst = src;
  dst.row(0) *= -1;
  const Similarity s = align_umeyama(src, dst, false);
  EXPECT_NEAR(s.rotation.determinant(), 1.0, 1e-12);
}
