#include "crowdslam/people/assignment.h"

#include <algorithm>
#include <cassert>
#include <limits>

namespace crowdslam::people {
namespace {

// Hungarian algorithm for n <= m (rows <= cols), 1-based potentials formulation.
std::vector<int> solve_rows_le_cols(const std::vector<std::vector<double>>& a, int n, int m) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> u(n + 1, 0.0), v(m + 1, 0.0);
  std::vector<int> p(m + 1, 0), way(m + 1, 0);
  for (int i = 1; i <= n; ++i) {
    p[0] = i;
    int j0 = 0;
    std::vector<double> minv(m + 1, inf);
    std::vector<char> used(m + 1, 0);
    do {
      used[j0] = 1;
      const int i0 = p[j0];
      double delta = inf;
      int j1 = 0;
      for (int j = 1; j <= m; ++j) {
        if (used[j]) continue;
        const double cur = a[i0 - 1][j - 1] - u[i0] - v[j];
        if (cur < minv[j]) {
          minv[j] = cur;
          way[j] = j0;
        }
        if (minv[j] < delta) {
          delta = minv[j];
          j1 = j;
        }
      }
      for (int j = 0; j <= m; ++j) {
        if (used[j]) {
          u[p[j]] += delta;
          v[j] -= delta;
        } else {
          minv[j] -= delta;
        }
      }
      j0 = j1;
    } while (p[j0] != 0);
    do {
      const int j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  std::vector<int> row_to_col(n, -1);
  for (int j = 1; j <= m; ++j)
    if (p[j] != 0) row_to_col[p[j] - 1] = j - 1;
  return row_to_col;
}

}  // namespace

std::vector<int> solve_assignment(const std::vector<std::vector<double>>& cost) {
  const int rows = static_cast<int>(cost.size());
  if (rows == 0) return {};
  const int cols = static_cast<int>(cost[0].size());
  for ([[maybe_unused]] const auto& r : cost) assert(static_cast<int>(r.size()) == cols);
  if (cols == 0) return std::vector<int>(rows, -1);
  if (rows <= cols) return solve_rows_le_cols(cost, rows, cols);
  std::vector<std::vector<double>> transposed(cols, std::vector<double>(rows));
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) transposed[c][r] = cost[r][c];
  const std::vector<int> col_to_row = solve_rows_le_cols(transposed, cols, rows);
  std::vector<int> row_to_col(rows, -1);
  for (int c = 0; c < cols; ++c)
    if (col_to_row[c] >= 0) row_to_col[col_to_row[c]] = c;
  return row_to_col;
}

std::vector<int> match_by_similarity(const std::vector<std::vector<double>>& similarity, double threshold) {
  const std::size_t rows = similarity.size();
  if (rows == 0) return {};
  const std::size_t cols = similarity[0].size();
  // Allowed costs are in [0, 1]; a forbidden pair costs more than any sum of allowed ones, so the optimum
  // has as many allowed pairs as possible.
  const double forbidden = static_cast<double>(std::max(rows, cols)) + 1.0;
  std::vector<std::vector<double>> cost(rows, std::vector<double>(cols, forbidden));
  for (std::size_t r = 0; r < rows; ++r)
    for (std::size_t c = 0; c < cols; ++c)
      if (similarity[r][c] >= threshold) cost[r][c] = 1.0 - similarity[r][c];
  std::vector<int> match = solve_assignment(cost);
  for (std::size_t r = 0; r < rows; ++r)
    if (match[r] >= 0 && !(similarity[r][static_cast<std::size_t>(match[r])] >= threshold)) match[r] = -1;
  return match;
}

}  // namespace crowdslam::people
