#include <gtest/gtest.h>

#include <random>

#include "crowdslam/bow/bow_vector.h"

namespace crowdslam::bow {
namespace {

TEST(L1Score, IdenticalVectorsScoreOne) {
  BowVector a{{1, 0.25}, {4, 0.5}, {9, 0.25}};
  EXPECT_DOUBLE_EQ(l1_score(a, a), 1.0);
}

TEST(L1Score, DisjointVectorsScoreZero) {
  BowVector a{{1, 0.5}, {2, 0.5}};
  BowVector b{{3, 0.3}, {4, 0.7}};
  EXPECT_DOUBLE_EQ(l1_score(a, b), 0.0);
  EXPECT_DOUBLE_EQ(l1_score(a, BowVector{}), 0.0);
}

TEST(L1Score, ClosedFormPartialOverlap) {
  // 1 - 0.5 * (|0.5 - 0.5| + 0.5 + 0.5) = 0.5
  EXPECT_DOUBLE_EQ(l1_score({{1, 0.5}, {2, 0.5}}, {{1, 0.5}, {3, 0.5}}), 0.5);
  // 1 - 0.5 * (|0.8 - 0.2| + 0.2 + 0.8) = 0.2
  EXPECT_NEAR(l1_score({{1, 0.8}, {2, 0.2}}, {{1, 0.2}, {3, 0.8}}), 0.2, 1e-12);
}

TEST(L1Score, SymmetricAndInUnitIntervalForRandomVectors) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    BowVector a;
    BowVector b;
    for (int i = 0; i < 20; ++i) {
      a[rng() % 30] += 1.0 + rng() % 5;
      b[rng() % 30] += 1.0 + rng() % 5;
    }
    normalize_l1(a);
    normalize_l1(b);
    const double ab = l1_score(a, b);
    EXPECT_DOUBLE_EQ(ab, l1_score(b, a));
    EXPECT_GE(ab, 0.0);
    EXPECT_LE(ab, 1.0);
    // Equivalent form for normalised vectors: sum over common words of min(a_i, b_i).
    double common = 0.0;
    for (const auto& [w, v] : a) {
      auto it = b.find(w);
      if (it != b.end()) common += std::min(v, it->second);
    }
    EXPECT_NEAR(ab, common, 1e-12);
  }
}

TEST(NormalizeL1, WeightsSumToOne) {
  BowVector a{{1, 2.0}, {5, 6.0}};
  normalize_l1(a);
  EXPECT_DOUBLE_EQ(a[1], 0.25);
  EXPECT_DOUBLE_EQ(a[5], 0.75);
}

}  // namespace
}  // namespace crowdslam::bow
