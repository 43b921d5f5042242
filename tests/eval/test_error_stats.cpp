#include <gtest/gtest.h>

#include <cmath>

#include "crowdslam/eval/error_stats.h"

using crowdslam::eval::compute_error_stats;
using crowdslam::eval::ErrorStats;

TEST(ErrorStats, OddCountMedianIsMiddleValue) {
  // {3, 1, 2}: sum 6, squares 14, deviations from mean 2: 1 + 1 + 0.
  const ErrorStats s = compute_error_stats({3.0, 1.0, 2.0});
  EXPECT_EQ(s.count, 3u);
  EXPECT_NEAR(s.rmse, std::sqrt(14.0 / 3.0), 1e-12);
  EXPECT_NEAR(s.mean, 2.0, 1e-12);
  EXPECT_EQ(s.median, 2.0);
  EXPECT_NEAR(s.std, std::sqrt(2.0 / 3.0), 1e-12);  // population (ddof = 0)
  EXPECT_EQ(s.min, 1.0);
  EXPECT_EQ(s.max, 3.0);
}

TEST(ErrorStats, EvenCountMedianIsMeanOfMiddleTwo) {
  // {4, 1, 10, 2}: sorted 1 2 4 10, median (2 + 4) / 2 = 3; mean 17/4; squares 121.
  const ErrorStats s = compute_error_stats({4.0, 1.0, 10.0, 2.0});
  EXPECT_EQ(s.median, 3.0);
  EXPECT_NEAR(s.mean, 4.25, 1e-12);
  EXPECT_NEAR(s.rmse, std::sqrt(121.0 / 4.0), 1e-12);
  EXPECT_NEAR(s.std, std::sqrt(121.0 / 4.0 - 4.25 * 4.25), 1e-12);
  EXPECT_EQ(s.min, 1.0);
  EXPECT_EQ(s.max, 10.0);
}

TEST(ErrorStats, ScaledMultipliesEveryStatistic) {
  const ErrorStats s = crowdslam::eval::scaled(compute_error_stats({1.0, 3.0}), 10.0);
  EXPECT_EQ(s.count, 2u);
  EXPECT_NEAR(s.mean, 20.0, 1e-12);
  EXPECT_NEAR(s.median, 20.0, 1e-12);
  EXPECT_NEAR(s.std, 10.0, 1e-12);
  EXPECT_NEAR(s.rmse, 10.0 * std::sqrt(5.0), 1e-12);
  EXPECT_EQ(s.min, 10.0);
  EXPECT_EQ(s.max, 30.0);
}
