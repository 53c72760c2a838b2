// The detector's box size as an observation of the shape (samp addition, not
// in the paper; docs/fitting.md, "Detected size"): a 3D detector measures each
// car's length, height and width with an error of std. dev. sigma (a stereo
// detector: ~0.3 m, the synthetic detector model's), so
//   E_size = w * || (s(z) - s_det) / sigma ||^2,
// s(z) the (length, height, width) of the shape's inside box, linearised about
// the code z0 of the solve (ShapeLookup::LineariseInsideBoxSize):
//   s(z) ~ s0 + J (z - z0),  residual = sqrt(w) / sigma (s0 + J (z - z0) - s_det),
//   d residual / d z = sqrt(w) / sigma J.
// Parameter block: z (R values).
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <cmath>

namespace samp {

class DetectionSizeCost : public ceres::CostFunction {
 public:
  DetectionSizeCost(const Eigen::VectorXd& z0, const Eigen::Vector3d& size0,
                    const Eigen::Matrix<double, 3, Eigen::Dynamic>& jacobian,
                    const Eigen::Vector3d& detected_size, double sigma, double weight)
      : z0_(z0), offset_(size0 - detected_size), scale_(std::sqrt(weight) / sigma), jacobian_(jacobian) {
    set_num_residuals(3);
    mutable_parameter_block_sizes()->push_back(int(z0.size()));
  }

  static ceres::CostFunction* Create(const Eigen::VectorXd& z0, const Eigen::Vector3d& size0,
                                     const Eigen::Matrix<double, 3, Eigen::Dynamic>& jacobian,
                                     const Eigen::Vector3d& detected_size, double sigma, double weight) {
    return new DetectionSizeCost(z0, size0, jacobian, detected_size, sigma, weight);
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const int n = int(z0_.size());
    const Eigen::Map<const Eigen::VectorXd> z(parameters[0], n);
    Eigen::Map<Eigen::Vector3d> r(residuals);
    r = scale_ * (offset_ + jacobian_ * (z - z0_));
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor>>(jacobians[0], 3, n) =
          scale_ * jacobian_;
    }
    return true;
  }

 private:
  Eigen::VectorXd z0_;
  Eigen::Vector3d offset_;
  double scale_;
  Eigen::Matrix<double, 3, Eigen::Dynamic> jacobian_;
};

}  // namespace samp
