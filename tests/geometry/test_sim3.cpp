#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "crowdslam/geometry/sim3.h"

using namespace crowdslam::geometry;

namespace {

Vec7 random_tangent(std::mt19937& rng, double max_angle, double max_log_scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec3 axis(u(rng), u(rng), u(rng));
  axis.normalize();
  Vec7 v;
  v << 2.0 * u(rng), 2.0 * u(rng), 2.0 * u(rng), 0.0, 0.0, 0.0, max_log_scale * u(rng);
  v.segment<3>(3) = max_angle * std::abs(u(rng)) * axis;
  return v;
}

// Largest difference of the 3x4 matrices [sR | t].
double distance(const Sim3& a, const Sim3& b) {
  const Mat3 ra = a.scale() * a.rotation_matrix();
  const Mat3 rb = b.scale() * b.rotation_matrix();
  return std::max((ra - rb).cwiseAbs().maxCoeff(), (a.translation() - b.translation()).cwiseAbs().maxCoeff());
}

// exp by numerical integration of W = integral_0^1 e^(sigma u) Exp(u phi) du (Simpson, 2000 intervals).
Vec3 integrated_translation(const Vec7& v) {
  const int n = 2000;
  Mat3 w = Mat3::Zero();
  for (int i = 0; i <= n; ++i) {
    const double u = static_cast<double>(i) / n;
    const double weight = (i == 0 || i == n) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    w += weight * std::exp(v(6) * u) * so3_exp(u * Vec3(v.segment<3>(3)));
  }
  w /= 3.0 * n;
  return w * v.head<3>();
}

}  // namespace

TEST(Sim3, ExpMatchesNumericalIntegral) {
  std::mt19937 rng(1);
  for (int i = 0; i < 20; ++i) {
    const Vec7 v = random_tangent(rng, 3.0, 1.5);
    const Sim3 s = Sim3::exp(v);
    EXPECT_NEAR(s.scale(), std::exp(v(6)), 1e-12);
    EXPECT_LT((s.rotation_matrix() - so3_exp(v.segment<3>(3))).norm(), 1e-12);
    EXPECT_LT((s.translation() - integrated_translation(v)).norm(), 1e-9) << v.transpose();
  }
}

TEST(Sim3, ExpWithZeroLogScaleIsSe3Exp) {
  std::mt19937 rng(2);
  for (int i = 0; i < 10; ++i) {
    Vec7 v = random_tangent(rng, 3.0, 0.0);
    v(6) = 0.0;
    const SE3 rigid = SE3::exp(v.head<6>());
    const Sim3 s = Sim3::exp(v);
    EXPECT_EQ(s.scale(), 1.0);
    EXPECT_LT(distance(s, Sim3(rigid)), 1e-12);
  }
}

TEST(Sim3, LogInvertsExp) {
  std::mt19937 rng(3);
  // Large, ordinary, small-angle and small-scale regimes (series branches included).
  const double angles[] = {3.0, 1.0, 1e-3, 1e-7, 0.0};
  const double log_scales[] = {3.0, 0.5, 1e-6, 0.0};
  for (const double angle : angles) {
    for (const double log_scale : log_scales) {
      for (int i = 0; i < 5; ++i) {
        const Vec7 v = random_tangent(rng, angle, log_scale);
        const Vec7 back = Sim3::exp(v).log();
        EXPECT_LT((back - v).norm(), 1e-9 * (1.0 + v.norm())) << v.transpose() << " / " << back.transpose();
      }
    }
  }
}

TEST(Sim3, ExpInvertsLog) {
  std::mt19937 rng(4);
  for (int i = 0; i < 20; ++i) {
    const Sim3 s(Eigen::Quaterniond::UnitRandom(), Vec3(1.0, -2.0, 0.5) * (i - 10) * 0.3,
                 std::exp(0.2 * (i - 10)));
    EXPECT_LT(distance(Sim3::exp(s.log()), s), 1e-10);
  }
}

TEST(Sim3, ExpIsAccurateAtTheSeriesThresholds) {
  // Either side of theta = 1e-3 and |sigma| = 2 (series vs closed forms), against the integral.
  const Vec3 rho(0.3, -0.7, 1.1);
  const Vec3 axis = Vec3(1.0, 2.0, -0.5).normalized();
  for (const double theta : {1e-3 - 1e-9, 1e-3 + 1e-9}) {
    for (const double sigma : {-2.0 - 1e-9, -2.0 + 1e-9, 0.4, 2.0 - 1e-9, 2.0 + 1e-9}) {
      Vec7 v;
      v << rho, theta * axis, sigma;
      EXPECT_LT((Sim3::exp(v).translation() - integrated_translation(v)).norm(), 1e-12)
          << theta << " " << sigma;
    }
  }
}

TEST(Sim3, CompositionActsLikeApplyingInTurn) {
  std::mt19937 rng(5);
  const Sim3 a_from_b = Sim3::exp(random_tangent(rng, 2.0, 0.7));
  const Sim3 b_from_c = Sim3::exp(random_tangent(rng, 2.0, 0.7));
  const Vec3 x(0.4, -1.3, 2.2);
  EXPECT_LT(((a_from_b * b_from_c) * x - a_from_b * (b_from_c * x)).norm(), 1e-12);
  EXPECT_NEAR((a_from_b * b_from_c).scale(), a_from_b.scale() * b_from_c.scale(), 1e-12);
}

TEST(Sim3, InverseIdentities) {
  std::mt19937 rng(6);
  const Sim3 a = Sim3::exp(random_tangent(rng, 2.5, 1.0));
  const Sim3 b = Sim3::exp(random_tangent(rng, 2.5, 1.0));
  EXPECT_LT(distance(a * a.inverse(), Sim3::identity()), 1e-12);
  EXPECT_LT(distance(a.inverse() * a, Sim3::identity()), 1e-12);
  EXPECT_LT(distance((a * b).inverse(), b.inverse() * a.inverse()), 1e-12);
  EXPECT_NEAR(a.inverse().scale(), 1.0 / a.scale(), 1e-15);
  const Vec3 x(-0.2, 0.9, 3.0);
  EXPECT_LT((a.inverse() * (a * x) - x).norm(), 1e-12);
  // exp(-v) = exp(v)^-1 (one-parameter subgroup).
  const Vec7 v = random_tangent(rng, 2.0, 0.8);
  EXPECT_LT(distance(Sim3::exp(-v), Sim3::exp(v).inverse()), 1e-12);
  EXPECT_LT((Sim3::exp(v).inverse().log() + v).norm(), 1e-10);
}

TEST(Sim3, ToSe3DividesTranslationByScale) {
  const Sim3 s(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Vec3::UnitZ())), Vec3(2.0, -4.0, 6.0), 2.0);
  const SE3 rigid = s.to_se3();
  EXPECT_LT((rigid.translation() - Vec3(1.0, -2.0, 3.0)).norm(), 1e-15);
  const Vec3 x(1.0, 1.0, 1.0);
  EXPECT_LT((rigid * x - (s * x) / 2.0).norm(), 1e-12);
}
