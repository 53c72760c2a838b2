#include "libsamp/core/assignment.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>

#include "libsamp/core/error.h"

namespace samp {
namespace {

// Hungarian method (shortest augmenting paths with potentials) for rows <= cols,
// finite costs. Returns for each row its column.
std::vector<int> HungarianRowsLeCols(const std::vector<double>& cost, int rows, int cols) {
  const double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> u(rows + 1, 0.0), v(cols + 1, 0.0), min_v(cols + 1);
  std::vector<int> row_of_col(cols + 1, 0), way(cols + 1, 0);
  std::vector<char> used(cols + 1);
  for (int i = 1; i <= rows; ++i) {
    row_of_col[0] = i;
    int j0 = 0;
    std::fill(min_v.begin(), min_v.end(), kInf);
    std::fill(used.begin(), used.end(), 0);
    do {
      used[j0] = 1;
      const int i0 = row_of_col[j0];
      double delta = kInf;
      int j1 = 0;
      for (int j = 1; j <= cols; ++j) {
        if (used[j]) continue;
        const double reduced = cost[(i0 - 1) * cols + (j - 1)] - u[i0] - v[j];
        if (reduced < min_v[j]) {
          min_v[j] = reduced;
          way[j] = j0;
        }
        if (min_v[j] < delta) {
          delta = min_v[j];
          j1 = j;
        }
      }
      for (int j = 0; j <= cols; ++j) {
        if (used[j]) {
          u[row_of_col[j]] += delta;
          v[j] -= delta;
        } else {
          min_v[j] -= delta;
        }
      }
      j0 = j1;
    } while (row_of_col[j0] != 0);
    do {
      const int j1 = way[j0];
      row_of_col[j0] = row_of_col[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  std::vector<int> col_of_row(rows, -1);
  for (int j = 1; j <= cols; ++j)
    if (row_of_col[j] != 0) col_of_row[row_of_col[j] - 1] = j - 1;
  return col_of_row;
}

}  // namespace

std::vector<int> SolveAssignment(const std::vector<double>& cost, int rows, int cols) {
  SAMP_CHECK(rows >= 0 && cols >= 0 && cost.size() == static_cast<size_t>(rows) * cols)
      << "SolveAssignment: cost matrix size " << cost.size() << " != " << rows << " x " << cols;
  std::vector<int> result(rows, -1);
  if (rows == 0 || cols == 0) return result;
  // Forbidden entries get a cost above any sum of allowed ones: the optimum
  // first maximises the number of allowed pairs, then minimises their cost.
  double sum_allowed = 0;
  for (double c : cost) {
    SAMP_CHECK(!std::isnan(c)) << "SolveAssignment: NaN cost";
    if (c < kNoAssignment) sum_allowed += std::abs(c);
  }
  const double big = 2 * sum_allowed + 1;
  const bool transpose = rows > cols;
  const int r = transpose ? cols : rows, c = transpose ? rows : cols;
  std::vector<double> work(static_cast<size_t>(r) * c);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) {
      const double value = cost[static_cast<size_t>(i) * cols + j];
      const double w = value < kNoAssignment ? value : big;
      if (transpose) work[static_cast<size_t>(j) * c + i] = w; else work[static_cast<size_t>(i) * c + j] = w;
    }
  const std::vector<int> assigned = HungarianRowsLeCols(work, r, c);
  for (int k = 0; k < r; ++k) {
    const int row = transpose ? assigned[k] : k;
    const int col = transpose ? k : assigned[k];
    if (row < 0 || col < 0) continue;
    if (cost[static_cast<size_t>(row) * cols + col] < kNoAssignment) result[row] = col;
  }
  return result;
}

std::vector<int> SolveSparseAssignment(const std::vector<SparseCost>& pairs, int rows, int cols) {
  std::vector<int> parent(rows + cols);
  for (int i = 0; i < rows + cols; ++i) parent[i] = i;
  std::function<int(int)> find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (const SparseCost& p : pairs) {
    const int a = find(p.row), b = find(rows + p.col);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
  std::map<int, std::pair<std::vector<int>, std::vector<int>>> groups;  // root -> rows, cols (increasing)
  for (const SparseCost& p : pairs) groups[find(p.row)];
  for (int r = 0; r < rows; ++r) {
    auto it = groups.find(find(r));
    if (it != groups.end()) it->second.first.push_back(r);
  }
  for (int c = 0; c < cols; ++c) {
    auto it = groups.find(find(rows + c));
    if (it != groups.end()) it->second.second.push_back(c);
  }
  std::vector<int> local_index(rows + cols, -1);
  for (const auto& [root, members] : groups) {
    for (size_t i = 0; i < members.first.size(); ++i) local_index[members.first[i]] = int(i);
    for (size_t j = 0; j < members.second.size(); ++j) local_index[rows + members.second[j]] = int(j);
  }
  std::map<int, std::vector<double>> matrices;
  for (const auto& [root, members] : groups)
    matrices[root].assign(members.first.size() * members.second.size(), kNoAssignment);
  for (const SparseCost& p : pairs) {
    const auto& members = groups.at(find(p.row));
    matrices[find(p.row)][size_t(local_index[p.row]) * members.second.size() + local_index[rows + p.col]] = p.cost;
  }
  std::vector<int> result(rows, -1);
  for (const auto& [root, members] : groups) {
    const int r = int(members.first.size()), c = int(members.second.size());
    const std::vector<int> local = SolveAssignment(matrices.at(root), r, c);
    for (int i = 0; i < r; ++i)
      if (local[i] >= 0) result[members.first[i]] = members.second[local[i]];
  }
  return result;
}

}  // namespace samp
