// The detector's box position as an observation of the pose (samp addition,
// not in the paper; docs/fitting.md, "Detected position"): a 3D detector measures each car's bottom centre p_det
// with covariance Sigma (world frame; TrackFrame::detection_covariance, the
// detector noise model the tracker gates with), so
//   E_position = w * (t + b - p_det)^T Sigma^-1 (t + b - p_det),
//   residual = sqrt(w) U (t + b - p_det),  U^T U = Sigma^-1 (Cholesky),
//   d residual / d(t, theta) = sqrt(w) (U, 0)   (b is a constant),
// b the detector's systematic offset in the world (its along-ray bias times
// the horizontal viewing ray of the detection: a detector that places boxes
// too far away has b along the ray; docs/detector_calibration.md, "Box
// conventions"; 0 = none).
// The term is what keeps a partly hidden or weakly textured car where the
// detector saw it when its few visible points fit a shape in several places
// (the visible top of a car behind another fits a shape with its cabin moved
// along the body as well as the true one).
// With FitOptions::detection_position_dead_zone > 0 (1 by default), within
// that many sigmas of its detection a frame's origin feels no pull
// (DeadZoneLoss below): the term still keeps a fit from a minimum of the data
// term metres away, but does not drag it within the detector's own
// uncertainty (docs/fitting.md, "Detected position").
// Parameter block: pose (tx, ty, tz, theta).
#pragma once

#include <ceres/loss_function.h>
#include <ceres/sized_cost_function.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace samp {

class DetectionPositionCost : public ceres::SizedCostFunction<3, 4> {
 public:
  // `covariance_in_world` must be symmetric positive definite; `bias_in_world` is b above.
  DetectionPositionCost(const Eigen::Vector3d& detected_position_in_world, const Eigen::Matrix3d& covariance_in_world,
                        double weight, const Eigen::Vector3d& bias_in_world = Eigen::Vector3d::Zero())
      : detected_(detected_position_in_world) {
    if (!bias_in_world.isZero(0.0)) detected_ -= bias_in_world;  // no bias: the same bits as without
    const Eigen::Matrix3d information = covariance_in_world.inverse();
    sqrt_information_ = std::sqrt(weight) * Eigen::Matrix3d(information.llt().matrixU());
  }

  static ceres::CostFunction* Create(const Eigen::Vector3d& detected_position_in_world,
                                     const Eigen::Matrix3d& covariance_in_world, double weight,
                                     const Eigen::Vector3d& bias_in_world = Eigen::Vector3d::Zero()) {
    return new DetectionPositionCost(detected_position_in_world, covariance_in_world, weight, bias_in_world);
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Map<const Eigen::Vector3d> t(parameters[0]);
    Eigen::Map<Eigen::Vector3d> r(residuals);
    r = sqrt_information_ * (t - detected_);
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, 3, 4, Eigen::RowMajor>> j(jacobians[0]);
      j.leftCols<3>() = sqrt_information_;
      j.col(3).setZero();
    }
    return true;
  }

 private:
  Eigen::Vector3d detected_;
  Eigen::Matrix3d sqrt_information_;
};

// The loss of a detected position with a dead zone (FitOptions::
// detection_position_dead_zone): on the block's squared norm s = w m^2
// (m the Mahalanobis distance of the origin from the detection),
//   rho(s) = (sqrt(s) - k)^2 for sqrt(s) > k, else 0,   k = sqrt(w) x the zone in sigmas,
//   rho'(s) = 1 - k / sqrt(s),   rho''(s) = k / (2 s sqrt(s))   (0 inside the zone).
// C^1 at the edge; beyond it the gradient is the Gaussian term's at m - zone.
class DeadZoneLoss : public ceres::LossFunction {
 public:
  explicit DeadZoneLoss(double k) : k_(k) {}
  void Evaluate(double s, double rho[3]) const override {
    const double r = std::sqrt(std::max(s, 0.0));
    if (r <= k_) {  // inside the zone (k >= 0, so also s = 0)
      rho[0] = rho[1] = rho[2] = 0.0;
      return;
    }
    rho[0] = (r - k_) * (r - k_);
    rho[1] = (r - k_) / r;
    rho[2] = k_ / (2.0 * s * r);
  }

 private:
  double k_;
};

}  // namespace samp
