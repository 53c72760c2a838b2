// The detector's box size as an observation of the shape (samp addition, not
// in the paper; docs/fitting.md, "Detected size"): a 3D detector measures each
// car's length, height and width with an error of std. dev. sigma (a stereo
// detector: ~0.3 m, the synthetic detector model's), so
//   E_size = w * || (s(z) + b - s_det) / sigma ||^2,
// s(z) the (length, height, width) of the shape's inside box, linearised about
// the code z0 of the solve (ShapeLookup::LineariseInsideBoxSize), b the
// detector's box convention: its mean box minus the shape's extent per
// dimension (KITTI's boxes exclude the mirrors that CAD extents include, so
// b_width < 0; docs/detector_calibration.md, "Box conventions"; 0 = the same):
//   s(z) ~ s0 + J (z - z0),  residual = sqrt(w) / sigma (s0 + J (z - z0) + b - s_det),
//   d residual / d z = sqrt(w) / sigma J   (b is a constant).
// Parameter block: z (R values).
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <cmath>

namespace samp {

class DetectionSizeCost : public ceres::CostFunction {
 public:
  // `bias`: b above, (length, height, width), m.
  DetectionSizeCost(const Eigen::VectorXd& z0, const Eigen::Vector3d& size0,
                    const Eigen::Matrix<double, 3, Eigen::Dynamic>& jacobian,
                    const Eigen::Vector3d& detected_size, double sigma, double weight,
                    const Eigen::Vector3d& bias = Eigen::Vector3d::Zero())
      : z0_(z0), offset_(size0 - detected_size), scale_(std::sqrt(weight) / sigma), jacobian_(jacobian) {
    if (!bias.isZero(0.0)) offset_ += bias;  // no bias: the offset's bits as without the term
    set_num_residuals(3);
    mutable_parameter_block_sizes()->push_back(int(z0.size()));
  }

  static ceres::CostFunction* Create(const Eigen::VectorXd& z0, const Eigen::Vector3d& size0,
                                     const Eigen::Matrix<double, 3, Eigen::Dynamic>& jacobian,
                                     const Eigen::Vector3d& detected_size, double sigma, double weight,
                                     const Eigen::Vector3d& bias = Eigen::Vector3d::Zero()) {
    return new DetectionSizeCost(z0, size0, jacobian, detected_size, sigma, weight, bias);
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
