#include <gtest/gtest.h>

#include "crowdslam/io/associate.h"

using namespace crowdslam::io;

TEST(Associate, GreedyBySmallestDifferenceEachStampOnce) {
  // 1.00 is closest to 1.005 (0.005) and 1.012 (0.012); 1.01 is closest to 1.012 (0.002).
  // Greedy order: (1.01,1.012) 0.002, then (1.00,1.005) 0.005.
  const std::vector<double> a{1.00, 1.01};
  const std::vector<double> b{1.012, 1.005};
  const auto m = associate_timestamps(a, b, 0.02);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].first_index, 0u);
  EXPECT_EQ(m[0].second_index, 1u);
  EXPECT_EQ(m[1].first_index, 1u);
  EXPECT_EQ(m[1].second_index, 0u);
}

TEST(Associate, MaxDifferenceIsStrict) {
  const auto m = associate_timestamps({1.0}, {1.25}, 0.25);
  EXPECT_TRUE(m.empty());
  EXPECT_EQ(associate_timestamps({1.0}, {1.2}, 0.25).size(), 1u);
}

TEST(Associate, UnsortedInputGivesResultSortedByFirstStamp) {
  const std::vector<double> a{3.0, 1.0, 2.0};
  const std::vector<double> b{2.001, 3.001, 1.001};
  const auto m = associate_timestamps(a, b, 0.02);
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(a[m[0].first_index], 1.0);
  EXPECT_EQ(b[m[0].second_index], 1.001);
  EXPECT_EQ(a[m[2].first_index], 3.0);
  EXPECT_EQ(b[m[2].second_index], 3.001);
}

TEST(Associate, OffsetShiftsSecondList) {
  const auto m = associate_timestamps({10.0}, {5.0}, 0.02, 5.0);
  EXPECT_EQ(m.size(), 1u);
}

TEST(Associate, DedupeLastWins) {
  const auto kept = dedupe_last_wins({2.0, 1.0, 2.0, 3.0});
  ASSERT_EQ(kept.size(), 3u);
  EXPECT_EQ(kept[0], 1u);
  EXPECT_EQ(kept[1], 2u);  // the later duplicate of 2.0
  EXPECT_EQ(kept[2], 3u);
}
