// Ground-plane prior of one frame (the paper's E_ground in its energy E): the
// car's origin (bottom centre) lies on that frame's road plane n . x + d = 0
// (world, n unit):
//   E_ground = w * ((n . t + d) / sigma_ground)^2,  residual = sqrt(w) (n . t + d) / sigma_ground,
//   d residual / d(t, theta) = sqrt(w) / sigma_ground * (n^T, 0).
// Parameter block: pose (tx, ty, tz, theta).
#pragma once

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <cmath>

namespace samp {

class GroundCost : public ceres::SizedCostFunction<1, 4> {
 public:
  GroundCost(const Eigen::Vector4d& plane_in_world, double sigma_ground, double weight)
      : plane_(plane_in_world), scale_(std::sqrt(weight) / sigma_ground) {}

  static ceres::CostFunction* Create(const Eigen::Vector4d& plane_in_world, double sigma_ground,
                                     double weight) {
    return new GroundCost(plane_in_world, sigma_ground, weight);
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double* t = parameters[0];
    residuals[0] = scale_ * (plane_[0] * t[0] + plane_[1] * t[1] + plane_[2] * t[2] + plane_[3]);
    if (jacobians && jacobians[0]) {
      for (int a = 0; a < 3; ++a) jacobians[0][a] = scale_ * plane_[a];
      jacobians[0][3] = 0.0;
    }
    return true;
  }

 private:
  Eigen::Vector4d plane_;
  double scale_;
};

}  // namespace samp
