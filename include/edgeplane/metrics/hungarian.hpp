// edgeplane: maximum-weight one-to-one assignment on a rectangular matrix (the Hungarian method of
// Kuhn and Munkres), used by D2MC to match segments to GT planes.  Host only, no I/O.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "edgeplane/error.hpp"

namespace edgeplane::metrics {

namespace detail {
/// cost(i, j) = -weight of the 1-based (i, j) of the n <= m working matrix (transposed or not).
struct assignment_cost {
  const std::int64_t* weights;
  std::size_t cols;  // of the caller's matrix
  bool transposed;
  std::int64_t operator()(std::size_t i, std::size_t j) const {
    return transposed ? -weights[(j - 1) * cols + (i - 1)] : -weights[(i - 1) * cols + (j - 1)];
  }
};
}  // namespace detail

/// Maximum-weight assignment of rows to columns of a dense row-major `rows` x `cols` matrix of
/// non-negative integer weights (pixel counts, say).  Returns, for each row, the column assigned to
/// it or -1.  Every row or every column (whichever side is smaller) is assigned: with non-negative
/// weights this loses nothing, and callers drop the zero-weight pairs they do not want.
///
/// Algorithm: the O(r^2 c) shortest-augmenting-path form of the Hungarian method with row and
/// column potentials (r = min(rows, cols), c = max(rows, cols)), on costs -w; integer arithmetic
/// throughout, so the optimum is exact.  Ties between optimal assignments are broken
/// deterministically (same input, same output).  Throws edgeplane::error when the matrix size
/// disagrees with `weights.size()` or a weight is negative.
inline std::vector<int> max_weight_assignment(std::span<const std::int64_t> weights, int rows, int cols) {
  edgeplane::detail::require(rows >= 0 && cols >= 0, "max_weight_assignment: negative matrix size " +
                                                         std::to_string(rows) + "x" + std::to_string(cols));
  edgeplane::detail::require(weights.size() == static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols),
                             "max_weight_assignment: " + std::to_string(weights.size()) + " weights for a " +
                                 std::to_string(rows) + "x" + std::to_string(cols) + " matrix");
  for (std::int64_t w : weights) edgeplane::detail::require(w >= 0, "max_weight_assignment: negative weight");

  std::vector<int> row_to_col(static_cast<std::size_t>(rows), -1);
  if (rows == 0 || cols == 0) return row_to_col;

  // Work on n <= m: transpose when there are more rows than columns.  Indices are 1-based below.
  const bool transposed = rows > cols;
  const std::size_t n = static_cast<std::size_t>(transposed ? cols : rows);
  const std::size_t m = static_cast<std::size_t>(transposed ? rows : cols);
  const detail::assignment_cost cost{weights.data(), static_cast<std::size_t>(cols), transposed};
  constexpr std::int64_t inf = std::numeric_limits<std::int64_t>::max() / 4;
  std::vector<std::int64_t> u(n + 1, 0), v(m + 1, 0);  // row and column potentials
  std::vector<std::size_t> p(m + 1, 0);                // p[j]: row matched to column j (0: none)
  std::vector<std::size_t> way(m + 1, 0);              // previous column on the augmenting path
  std::vector<std::int64_t> minv(m + 1);
  std::vector<char> used(m + 1);
  for (std::size_t i = 1; i <= n; ++i) {
    // Add row i: grow a shortest-path tree (Dijkstra on reduced costs) from the virtual column 0
    // until it reaches a free column, updating the potentials so reduced costs stay >= 0.
    p[0] = i;
    std::size_t j0 = 0;
    std::fill(minv.begin(), minv.end(), inf);
    std::fill(used.begin(), used.end(), 0);
    do {
      used[j0] = 1;
      const std::size_t i0 = p[j0];
      std::int64_t delta = inf;
      std::size_t j1 = 0;
      for (std::size_t j = 1; j <= m; ++j) {
        if (used[j]) continue;
        const std::int64_t cur = cost(i0, j) - u[i0] - v[j];
        if (cur < minv[j]) {
          minv[j] = cur;
          way[j] = j0;
        }
        if (minv[j] < delta) {
          delta = minv[j];
          j1 = j;
        }
      }
      for (std::size_t j = 0; j <= m; ++j) {
        if (used[j]) {
          u[p[j]] += delta;
          v[j] -= delta;
        } else {
          minv[j] -= delta;
        }
      }
      j0 = j1;
    } while (p[j0] != 0);
    // Augment along the path back to column 0.
    do {
      const std::size_t j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  for (std::size_t j = 1; j <= m; ++j) {
    const std::size_t i = p[j];
    if (i == 0) continue;
    if (transposed)
      row_to_col[j - 1] = static_cast<int>(i - 1);
    else
      row_to_col[i - 1] = static_cast<int>(j - 1);
  }
  return row_to_col;
}

}  // namespace edgeplane::metrics
