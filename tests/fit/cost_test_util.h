// Test helpers of the cost functors (tests/fit/costs/): the synthetic model
// and its lookup, and analytic Jacobians checked against central differences.
#pragma once

#include <ceres/cost_function.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "libsamp/fit/costs/data_cost.h"
#include "libsamp/model/shape_lookup.h"
#include "tests/fit/fit_test_util.h"

namespace samp::testing {

inline const ShapeModel& CostModel() {
  static const ShapeModel model = MakeSyntheticModel(5, 0.1);
  return model;
}
inline const ShapeLookup& CostLookup() {
  static const ShapeLookup lookup(CostModel());
  return lookup;
}

// Data-term options with Huber threshold k and weight w (the rest default).
inline DataCostOptions HuberOptions(double k, double w) {
  DataCostOptions o;
  o.huber_threshold = k;
  o.weight = w;
  return o;
}

// Analytic Jacobians vs central differences (step 1e-6, absolute), entry by
// entry: |analytic - numeric| <= tolerance * max(1, |numeric|). (Own central
// differences rather than ceres::GradientChecker, whose relative step is
// scaled by |x| and so too coarse for world coordinates of ~15 m on a 0.1 m
// piecewise-trilinear field.)
inline void ExpectJacobiansMatch(const ceres::CostFunction& cost, std::vector<double*> params,
                          double tolerance, const std::string& what) {
  const int num_residuals = cost.num_residuals();
  const std::vector<int32_t>& sizes = cost.parameter_block_sizes();
  ASSERT_EQ(sizes.size(), params.size());
  std::vector<std::vector<double>> jacobians(sizes.size());
  std::vector<double*> jacobian_ptrs(sizes.size());
  for (size_t b = 0; b < sizes.size(); ++b) {
    jacobians[b].assign(size_t(num_residuals) * sizes[b], 0.0);
    jacobian_ptrs[b] = jacobians[b].data();
  }
  std::vector<double> r0(num_residuals), rp(num_residuals), rm(num_residuals);
  ASSERT_TRUE(cost.Evaluate(params.data(), r0.data(), jacobian_ptrs.data())) << what;
  int bad = 0;
  double worst = 0.0;
  std::ostringstream log;
  for (size_t b = 0; b < sizes.size(); ++b) {
    for (int k = 0; k < sizes[b]; ++k) {
      const double h = 1e-6, saved = params[b][k];
      params[b][k] = saved + h;
      ASSERT_TRUE(cost.Evaluate(params.data(), rp.data(), nullptr));
      params[b][k] = saved - h;
      ASSERT_TRUE(cost.Evaluate(params.data(), rm.data(), nullptr));
      params[b][k] = saved;
      for (int i = 0; i < num_residuals; ++i) {
        const double numeric = (rp[i] - rm[i]) / (2 * h);
        const double analytic = jacobians[b][size_t(i) * sizes[b] + k];
        const double error = std::abs(analytic - numeric) / std::max(1.0, std::abs(numeric));
        worst = std::max(worst, error);
        if (error > tolerance) {
          if (bad < 5) log << " block " << b << " row " << i << " col " << k << ": " << analytic << " vs " << numeric << "\n";
          ++bad;
        }
      }
    }
  }
  EXPECT_EQ(bad, 0) << what << ": worst error " << worst << "\n" << log.str();
}

}  // namespace samp::testing
