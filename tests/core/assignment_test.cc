#include "libsamp/core/assignment.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "libsamp/core/error.h"
#include "tests/testing/expect_error.h"

namespace samp {
namespace {

// Brute force: best (max count, then min cost) assignment.
void BruteForce(const std::vector<double>& cost, int rows, int cols, int* best_count, double* best_cost) {
  *best_count = -1;
  *best_cost = 0;
  std::vector<int> assignment(rows, -1);
  std::vector<char> used(cols, 0);
  std::function<void(int, int, double)> recurse = [&](int row, int count, double total) {
    if (row == rows) {
      if (count > *best_count || (count == *best_count && total < *best_cost - 1e-12)) {
        *best_count = count;
        *best_cost = total;
      }
      return;
    }
    recurse(row + 1, count, total);
    for (int c = 0; c < cols; ++c) {
      const double value = cost[row * cols + c];
      if (used[c] || value >= kNoAssignment) continue;
      used[c] = 1;
      recurse(row + 1, count + 1, total + value);
      used[c] = 0;
    }
  };
  recurse(0, 0, 0.0);
}

TEST(Assignment, HungarianMatchesBruteForce) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> value(0, 10), coin(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const int rows = 1 + trial % 5, cols = 1 + (trial / 5) % 6;
    std::vector<double> cost(rows * cols);
    for (double& c : cost) c = coin(rng) < 0.3 ? kNoAssignment : value(rng);
    const std::vector<int> result = SolveAssignment(cost, rows, cols);
    ASSERT_EQ(static_cast<int>(result.size()), rows);
    int count = 0;
    double total = 0;
    std::vector<char> used(cols, 0);
    for (int r = 0; r < rows; ++r) {
      if (result[r] < 0) continue;
      ASSERT_LT(result[r], cols);
      ASSERT_FALSE(used[result[r]]);
      used[result[r]] = 1;
      ASSERT_LT(cost[r * cols + result[r]], kNoAssignment);
      ++count;
      total += cost[r * cols + result[r]];
    }
    int best_count;
    double best_cost;
    BruteForce(cost, rows, cols, &best_count, &best_cost);
    EXPECT_EQ(count, best_count) << "trial " << trial;
    EXPECT_NEAR(total, best_cost, 1e-9) << "trial " << trial;
  }
  EXPECT_TRUE(SolveAssignment({}, 0, 3).empty());
  EXPECT_EQ(SolveAssignment({}, 2, 0), std::vector<int>({-1, -1}));
}

// The sparse solver over the allowed entries of random matrices gives the
// dense solver's count and cost (it solves each connected group on its own).
TEST(Assignment, SparseMatchesDense) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> value(0, 10), coin(0, 1);
  for (int trial = 0; trial < 300; ++trial) {
    const int rows = 1 + trial % 7, cols = 1 + (trial / 7) % 8;
    const double forbidden = 0.3 + 0.5 * coin(rng);  // sparse enough to split into groups
    std::vector<double> cost(rows * cols);
    std::vector<SparseCost> pairs;
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) {
        cost[r * cols + c] = coin(rng) < forbidden ? kNoAssignment : value(rng);
        if (cost[r * cols + c] < kNoAssignment) pairs.push_back({r, c, cost[r * cols + c]});
      }
    const std::vector<int> dense = SolveAssignment(cost, rows, cols);
    const std::vector<int> sparse = SolveSparseAssignment(pairs, rows, cols);
    ASSERT_EQ(int(sparse.size()), rows);
    auto score = [&](const std::vector<int>& a, int* count, double* total) {
      *count = 0;
      *total = 0;
      std::vector<char> used(cols, 0);
      for (int r = 0; r < rows; ++r) {
        if (a[r] < 0) continue;
        ASSERT_FALSE(used[a[r]]) << "trial " << trial;
        used[a[r]] = 1;
        ASSERT_LT(cost[r * cols + a[r]], kNoAssignment) << "trial " << trial;
        ++*count;
        *total += cost[r * cols + a[r]];
      }
    };
    int dense_count, sparse_count;
    double dense_total, sparse_total;
    score(dense, &dense_count, &dense_total);
    score(sparse, &sparse_count, &sparse_total);
    EXPECT_EQ(sparse_count, dense_count) << "trial " << trial;
    EXPECT_NEAR(sparse_total, dense_total, 1e-9) << "trial " << trial;
  }
  EXPECT_EQ(SolveSparseAssignment({}, 3, 2), std::vector<int>({-1, -1, -1}));
}

TEST(Assignment, BadInputIsAnError) {
  test::ExpectError([] { SolveAssignment({1.0, 2.0, 3.0}, 2, 2); }, {"cost matrix size 3", "2 x 2"});
  test::ExpectError([] { SolveAssignment({1.0, std::nan("")}, 1, 2); }, {"NaN cost"});
}

}  // namespace
}  // namespace samp
