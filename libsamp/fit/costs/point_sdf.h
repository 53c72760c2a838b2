// The paper's data term (SAMP Section 3.2, E_data): the signed distance of
// each point to the shape, in the object frame,
//   s_i = phi_z(R_y(theta)^T (x_i - t)) / sigma_i,
//   E_data = w / N * sum_i rho(s_i)          (rho: Huber, or the mixture; data_cost.h)
// with phi_z the trilinear lookup of ShapeLookup (outside the grid: the value
// grows with the distance to the grid box, the gradient points back).
// Jacobians (o = the point in the object frame):
//   d r_i / d z     =  sqrt(w/N) psi'(s_i) / sigma_i * d phi / d z  (trilinear weights on W)
//   d r_i / d t     = -sqrt(w/N) psi'(s_i) / sigma_i * (R grad phi)^T
//   d r_i / d theta =  sqrt(w/N) psi'(s_i) / sigma_i * grad phi . (-o_z, 0, o_x)
#pragma once

#include <vector>

#include "libsamp/fit/costs/data_cost.h"

namespace samp {

class PointSdfCost : public DataCost {
 public:
  // `lookup` must outlive the cost. points and sigmas have equal, non-zero size.
  PointSdfCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
               const std::vector<double>& sigmas, const DataCostOptions& options)
      : DataCost(lookup, points_in_world, sigmas, options, /*with_rays=*/false) {}

  bool EvaluateRows(const double* z, const double* pose, int begin, int end, double* residuals, double* jz,
                    int jz_stride, double* jp, int jp_stride) const override;
};

}  // namespace samp
