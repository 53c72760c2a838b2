// Linear assignment: the least-cost one-to-one pairing of rows and columns.
// Used by the tracker (data/tracking.cc), the detector-noise estimator and
// the evaluation's matching (eval/). Stateless and thread-safe.
#pragma once

#include <vector>

namespace samp {

// Entries of a cost matrix at or above this value are forbidden pairs.
constexpr double kNoAssignment = 1e18;

// Minimum-cost assignment (Hungarian method, O(n^3)) on a rows x cols cost
// matrix (row-major); entries >= kNoAssignment are forbidden. Returns for each
// row the assigned column or -1. The assignment has the largest number of
// allowed pairs and, among those, the least total cost. Throws samp::Error on
// a matrix of the wrong size or a NaN cost.
std::vector<int> SolveAssignment(const std::vector<double>& cost, int rows, int cols);

// One allowed pair of a sparse cost list.
struct SparseCost {
  int row, col;
  double cost;
};

// The least-cost assignment of a sparse cost list (allowed pairs only), solved
// per connected group of rows and columns: the same optimum as
// SolveAssignment over the dense matrix, in time linear in the number of
// groups of bounded size. Returns the column of each row or -1.
std::vector<int> SolveSparseAssignment(const std::vector<SparseCost>& pairs, int rows, int cols);

}  // namespace samp
