// Shape prior of the PCA manifold (the paper's E_shape in its energy E): E_shape = lambda * sum_i (z_i / sigma_i)^2,
// sigma_i^2 the eigenvalues; residual_i = sqrt(lambda) z_i / sigma_i,
// d residual_i / d z_j = sqrt(lambda) / sigma_i if i == j else 0.
// Parameter block: z (R values).
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <cmath>

namespace samp {

class ShapePriorCost : public ceres::CostFunction {
 public:
  ShapePriorCost(const Eigen::VectorXd& sigmas, double weight)
      : scales_(std::sqrt(weight) * sigmas.cwiseInverse()) {
    set_num_residuals(int(sigmas.size()));
    mutable_parameter_block_sizes()->push_back(int(sigmas.size()));
  }

  static ceres::CostFunction* Create(const Eigen::VectorXd& sigmas, double weight) {
    return new ShapePriorCost(sigmas, weight);
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const int n = int(scales_.size());
    for (int i = 0; i < n; ++i) residuals[i] = scales_[i] * parameters[0][i];
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::MatrixXd>(jacobians[0], n, n) = scales_.asDiagonal();
    }
    return true;
  }

 private:
  Eigen::VectorXd scales_;
};

}  // namespace samp
