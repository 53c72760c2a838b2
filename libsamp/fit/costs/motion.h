// Motion term between consecutive frames of a track (SAMP Section 3.3, E_motion):
//   E_motion = w * || xi_t - g(xi_{t-1}) ||^2_Sigma,
//   e = (t_t - g_t, wrap(theta_t - g_theta), v_t - g_v, omega_t - g_omega),
//   residual = sqrt(w) L e,  L^T L = Sigma^-1 (L upper triangular),
// with g the chosen motion model (motion_model.h). The model and Sigma are
// fixed per cost (evaluated at the linearisation point by the fitter before a
// solve) so that the term is a plain least-squares residual; the yaw
// difference is wrapped to (-pi, pi] (its derivative is unaffected).
// Jacobians: d r / d(pose_t, v_t) = sqrt(w) L,  d r / d(pose_{t-1}, v_{t-1}) =
// -sqrt(w) L dg/d(pose, v). Parameter blocks: pose_{t-1} (4), velocity_{t-1}
// (2), pose_t (4), velocity_t (2).
#pragma once

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <cmath>

#include "libsamp/fit/motion_model.h"

namespace samp {

class MotionCost : public ceres::SizedCostFunction<6, 4, 2, 4, 2> {
 public:
  MotionCost(MotionModel model, double dt, const Eigen::Matrix<double, 6, 6>& sqrt_information,
             double weight)
      : model_(model), dt_(dt), sqrt_information_(std::sqrt(weight) * sqrt_information) {}

  static ceres::CostFunction* Create(MotionModel model, double dt,
                                     const Eigen::Matrix<double, 6, 6>& sqrt_information,
                                     double weight) {
    return new MotionCost(model, dt, sqrt_information, weight);
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    double predicted[6];
    Eigen::Matrix<double, 6, 4, Eigen::RowMajor> d_pose;
    Eigen::Matrix<double, 6, 2, Eigen::RowMajor> d_velocity;
    const bool need_prev = jacobians && (jacobians[0] || jacobians[1]);
    PredictMotion(model_, parameters[0], parameters[1], dt_, predicted,
                  need_prev ? d_pose.data() : nullptr, need_prev ? d_velocity.data() : nullptr);
    Eigen::Matrix<double, 6, 1> e;
    for (int k = 0; k < 4; ++k) e[k] = parameters[2][k] - predicted[k];
    e[3] = WrapAngle(e[3]);
    e[4] = parameters[3][0] - predicted[4];
    e[5] = parameters[3][1] - predicted[5];
    Eigen::Map<Eigen::Matrix<double, 6, 1>> r(residuals);
    r = sqrt_information_ * e;
    if (!jacobians) return true;
    if (jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, 6, 4, Eigen::RowMajor>> j(jacobians[0]);
      j = -sqrt_information_ * d_pose;
    }
    if (jacobians[1]) {
      Eigen::Map<Eigen::Matrix<double, 6, 2, Eigen::RowMajor>> j(jacobians[1]);
      j = -sqrt_information_ * d_velocity;
    }
    if (jacobians[2]) {
      Eigen::Map<Eigen::Matrix<double, 6, 4, Eigen::RowMajor>> j(jacobians[2]);
      j = sqrt_information_.leftCols<4>();
    }
    if (jacobians[3]) {
      Eigen::Map<Eigen::Matrix<double, 6, 2, Eigen::RowMajor>> j(jacobians[3]);
      j = sqrt_information_.rightCols<2>();
    }
    return true;
  }

 private:
  MotionModel model_;
  double dt_;
  Eigen::Matrix<double, 6, 6> sqrt_information_;  // includes sqrt(w)
};

}  // namespace samp
