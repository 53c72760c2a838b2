// A data term (data_cost.h) compressed to R + 5 residuals with identical cost,
// gradient and Gauss-Newton Hessian (samp addition, for speed; the paper's
// energy is unchanged), so Ceres' linear algebra works on a (R + 4)-row block
// instead of an N-row one (the per-point work stays): with J, r the N-row
// Jacobian and residuals of the data term at the current parameters,
// H = J^T J + eps I = L L^T (Cholesky, eps = 1e-12 trace(H)),
//   residuals  = (L^-1 J^T r, sqrt(max(0, |r|^2 - |L^-1 J^T r|^2)))
//   Jacobian   = (L^T; 0)
// => |residuals|^2 = |r|^2 (the cost), Jacobian^T residuals = J^T r (the
// gradient), Jacobian^T Jacobian = H (the Gauss-Newton matrix), and
// |Jacobian d + residuals|^2 = |J d + r|^2 for every step d, so
// Levenberg-Marquardt takes exactly the steps of the uncompressed problem.
// The returned Jacobian is NOT the derivative of the returned residuals
// (those depend on the linearisation point); tests compare cost, gradient
// and J^T J with the data term instead of numeric differentiation.
// Eager linearisation: every evaluation, also a cost-only one, computes the
// Jacobian and keeps the result for its parameters. Levenberg-Marquardt
// evaluates the cost of each trial step and then, when the step is accepted
// (almost always with this data term), the Jacobian at the same parameters:
// that second call is a copy. One Evaluate at a time per block (a mutex).
#pragma once

#include <ceres/cost_function.h>

#include <memory>
#include <mutex>
#include <vector>

#include "libsamp/fit/costs/data_cost.h"

namespace samp {

class CompressedDataCost : public ceres::CostFunction {
 public:
  explicit CompressedDataCost(std::unique_ptr<DataCost> full);

  // The data term options.term selects (MakeDataCost), compressed.
  static ceres::CostFunction* Create(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
                                     const std::vector<double>& sigmas, const DataCostOptions& options) {
    return new CompressedDataCost(MakeDataCost(lookup, points_in_world, sigmas, options));
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  // Residuals and Jacobians at (z, pose) into the cache; false when not finite.
  bool Linearize(const double* z, const double* pose) const;

  std::unique_ptr<DataCost> full_;
  int num_components_;
  mutable std::mutex cache_mutex_;
  mutable bool cache_valid_ = false;
  mutable std::vector<double> cache_parameters_;     // z, then pose
  mutable std::vector<double> cache_residuals_;      // R + 5
  mutable std::vector<double> cache_jz_, cache_jp_;  // (R + 5) x R, (R + 5) x 4, row-major
};

}  // namespace samp
