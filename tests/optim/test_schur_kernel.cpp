#include <gtest/gtest.h>

#include <Eigen/Core>
#include <random>
#include <string>
#include <vector>

#include "crowdslam/optim/schur_kernel.h"

using namespace crowdslam::optim;

namespace {

using Mat63 = Eigen::Matrix<double, 6, 3>;

// The reference: the Schur pair update written with Eigen blocks, as the header states it.
void reference(const std::vector<Mat63>& y, const std::vector<Mat63>& w, const std::vector<int>& pose,
               Eigen::MatrixXd& s) {
  const int m = static_cast<int>(pose.size());
  for (int a = 0; a < m; ++a) {
    for (int b = a; b < m; ++b) {
      const Eigen::Matrix<double, 6, 6> block = y[a] * w[b].transpose();
      const int fa = pose[a];
      const int fb = pose[b];
      if (a == b || fa < fb) {
        s.block<6, 6>(6 * fa, 6 * fb) -= block;
      } else if (fa > fb) {
        s.block<6, 6>(6 * fb, 6 * fa) -= block.transpose();
      } else {
        s.block<6, 6>(6 * fa, 6 * fa) -= block + block.transpose();
      }
    }
  }
}

// Random points over `num_free` poses, observed in a shuffled pose order and sometimes twice by one pose,
// so every branch (fa < fb, fa > fb, fa == fb with a != b, a == b) is taken.
void check_variant(schur_kernel::SubtractPairs subtract, const std::string& name) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> value(-2.0, 2.0);
  const int num_free = 5;
  Eigen::MatrixXd expected = Eigen::MatrixXd::Random(6 * num_free, 6 * num_free);
  Eigen::MatrixXd actual = expected;
  int pairs_seen[3] = {0, 0, 0};  // fa < fb, fa > fb, fa == fb (a != b)
  for (int point = 0; point < 40; ++point) {
    const int m = 1 + point % 7;
    std::vector<Mat63> y(m), w(m);
    std::vector<int> pose(m);
    std::vector<double> y_flat(18 * m), w_flat(18 * m);
    for (int a = 0; a < m; ++a) {
      for (int k = 0; k < 18; ++k) {
        y[a].data()[k] = value(rng);
        w[a].data()[k] = value(rng);
      }
      pose[a] = static_cast<int>(rng() % num_free);
      std::copy(y[a].data(), y[a].data() + 18, y_flat.begin() + 18 * a);
      std::copy(w[a].data(), w[a].data() + 18, w_flat.begin() + 18 * a);
      for (int b = 0; b < a; ++b) ++pairs_seen[pose[b] < pose[a] ? 0 : pose[b] > pose[a] ? 1 : 2];
    }
    reference(y, w, pose, expected);
    subtract({y_flat.data(), w_flat.data(), pose.data(), m}, actual.data(), actual.outerStride());
  }
  EXPECT_GT(pairs_seen[0], 0);
  EXPECT_GT(pairs_seen[1], 0);
  EXPECT_GT(pairs_seen[2], 0);
  // Upper and lower triangle alike (the kernel must not write below the block diagonal's upper half
  // any more than the reference does); FMA contraction may round the last bit differently.
  EXPECT_LT((actual - expected).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + expected.cwiseAbs().maxCoeff()))
      << name;
}

}  // namespace

TEST(SchurKernel, BaselineMatchesTheEigenReference) {
  check_variant(&schur_kernel::subtract_pairs_baseline, "baseline");
}

TEST(SchurKernel, Avx2FmaMatchesTheEigenReferenceWhereTheCpuHasIt) {
  const auto avx2 = schur_kernel::subtract_pairs_avx2_fma();
  if (avx2 == nullptr) GTEST_SKIP() << "this CPU has no AVX2 + FMA";
  check_variant(avx2, "avx2+fma");
}

TEST(SchurKernel, TheChosenVariantIsTheFastestThisCpuRuns) {
  const auto avx2 = schur_kernel::subtract_pairs_avx2_fma();
  EXPECT_EQ(schur_kernel::subtract_pairs(), avx2 != nullptr ? avx2 : &schur_kernel::subtract_pairs_baseline);
  EXPECT_STREQ(schur_kernel::subtract_pairs_variant(), avx2 != nullptr ? "avx2+fma" : "baseline");
}
