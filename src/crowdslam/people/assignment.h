#pragma once
// Minimum-cost assignment (Hungarian algorithm with potentials, O(n^3)) on a rectangular cost matrix.
#include <vector>

namespace crowdslam::people {

// cost[r][c]; all rows the same length. Returns, for each row, the assigned column or -1 (when there are
// more rows than columns). Every column is used at most once and the total cost of the assignment is
// minimal among assignments of min(rows, cols) pairs.
std::vector<int> solve_assignment(const std::vector<std::vector<double>>& cost);

// Matching for detection metrics: pairs with similarity >= threshold may be matched. Returns, for each
// row, the matched column or -1. Maximises the number of matches first, then the total similarity
// (the Hungarian algorithm on cost 1 - similarity, with a forbidden cost larger than any total of
// allowed costs).
std::vector<int> match_by_similarity(const std::vector<std::vector<double>>& similarity, double threshold);

}  // namespace crowdslam::people
