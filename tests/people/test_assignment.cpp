// Hungarian assignment: optimal where greedy is not, rectangular matrices, similarity thresholds.
#include <gtest/gtest.h>

#include <algorithm>

#include "crowdslam/people/assignment.h"

namespace crowdslam::people {
namespace {

double total(const std::vector<std::vector<double>>& cost, const std::vector<int>& m) {
  double sum = 0;
  for (std::size_t r = 0; r < m.size(); ++r)
    if (m[r] >= 0) sum += cost[r][static_cast<std::size_t>(m[r])];
  return sum;
}

TEST(SolveAssignment, FindsTheMinimumOfAllPermutations) {
  // Compared with a brute-force search over all 3! permutations.
  const std::vector<std::vector<double>> cost = {{4, 1, 3}, {2, 0, 5}, {3, 2, 2}};
  const auto m = solve_assignment(cost);
  std::vector<int> perm = {0, 1, 2};
  double best = 1e9;
  do {
    best = std::min(best, cost[0][perm[0]] + cost[1][perm[1]] + cost[2][perm[2]]);
  } while (std::next_permutation(perm.begin(), perm.end()));
  EXPECT_DOUBLE_EQ(total(cost, m), best);
  EXPECT_DOUBLE_EQ(best, 5.0);  // 1 + 2 + 2
}

TEST(SolveAssignment, RectangularBothWays) {
  const std::vector<std::vector<double>> wide = {{5, 1, 9}, {1, 6, 9}};
  EXPECT_EQ(solve_assignment(wide), (std::vector<int>{1, 0}));
  const std::vector<std::vector<double>> tall = {{5, 1}, {1, 6}, {0.5, 0.4}};
  // Best pair of rows: 1 and 2 (1 + 0.4 = 1.4) beats rows 0 and 2 (1 + 0.5) and rows 0 and 1 (2).
  EXPECT_EQ(solve_assignment(tall), (std::vector<int>{-1, 0, 1}));
  EXPECT_TRUE(solve_assignment({}).empty());
}

TEST(MatchBySimilarity, GlobalOptimumWhereGreedyFails) {
  // Greedy takes (0,0) = 0.9 and then row 1 has nothing >= 0.5; the assignment matches both rows.
  const std::vector<std::vector<double>> iou = {{0.9, 0.6}, {0.7, 0.2}};
  EXPECT_EQ(match_by_similarity(iou, 0.5), (std::vector<int>{1, 0}));
}

TEST(MatchBySimilarity, MoreMatchesBeatHigherTotalSimilarity) {
  // Matching all three rows at 0.5 each (total 1.5) vs (0,0) + (1,1) at 1.0 each (total 2.0): the
  // number of matches wins (a detection metric counts true positives first).
  const std::vector<std::vector<double>> iou = {{1.0, 0.5, 0.0}, {0.0, 1.0, 0.5}, {0.5, 0.0, 0.0}};
  const auto m = match_by_similarity(iou, 0.5);
  EXPECT_EQ(m, (std::vector<int>{1, 2, 0}));
}

TEST(MatchBySimilarity, PairsBelowThresholdAreNotMatched) {
  const std::vector<std::vector<double>> iou = {{0.49, 0.0}, {0.0, 0.3}};
  EXPECT_EQ(match_by_similarity(iou, 0.5), (std::vector<int>{-1, -1}));
  EXPECT_EQ(match_by_similarity(iou, 0.3), (std::vector<int>{0, 1}));
}

}  // namespace
}  // namespace crowdslam::people
