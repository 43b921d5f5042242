#include <gtest/gtest.h>

#include "crowdslam/geometry/se3.h"

using namespace crowdslam::geometry;

TEST(SE3, ExpLogRoundTrip) {
  Vec6 twist;
  twist << 0.3, -0.2, 1.1, 0.4, -0.7, 0.2;
  const SE3 t = SE3::exp(twist);
  EXPECT_LT((t.log() - twist).norm(), 1e-12);
}

TEST(SE3, InverseComposesToIdentity) {
  Vec6 twist;
  twist << 1, 2, 3, 0.1, 0.2, 0.3;
  const SE3 t = SE3::exp(twist);
  const SE3 id = t * t.inverse();
  EXPECT_LT(id.translation().norm(), 1e-12);
  EXPECT_LT(rotation_angle(id.rotation_matrix()), 1e-7);
  const Vec3 p(0.5, -1, 2);
  EXPECT_LT((t.inverse() * (t * p) - p).norm(), 1e-12);
}

TEST(SE3, PureRotationAboutZ) {
  Vec6 twist = Vec6::Zero();
  twist(5) = M_PI / 2;
  const SE3 t = SE3::exp(twist);
  EXPECT_LT((t * Vec3(1, 0, 0) - Vec3(0, 1, 0)).norm(), 1e-12);
  EXPECT_NEAR(rotation_angle(t.rotation_matrix()), M_PI / 2, 1e-12);
}

TEST(SE3, MatrixRoundTrip) {
  Vec6 twist;
  twist << -1, 0.5, 0.25, -0.3, 0.9, 0.1;
  const SE3 t = SE3::exp(twist);
  const SE3 u(t.matrix());
  EXPECT_LT((u.matrix() - t.matrix()).norm(), 1e-12);
}
