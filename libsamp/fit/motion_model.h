// Vehicle motion models of SAMP (WACV 2017, Section 3.3) and the frame
// conventions of a fitted pose.
//
// Pose of a car in the world: translation t (origin of the canonical object
// frame = bottom centre of the car; object x front, y down, z left) and yaw
// theta about the world's vertical axis y (KITTI's rotation_y convention):
//   world_from_object = [R_y(theta) | t],  R_y = [[c, 0, s], [0, 1, 0], [-s, 0, c]],
// so the car's heading (object +x) in the world is h(theta) = (cos, 0, -sin).
// Velocities: speed v along the heading (m/s) and yaw rate omega (rad/s).
//
// Models g(xi) predicting xi_t = (t, theta, v, omega) from xi_{t-1} over dt:
//   standing: (t, theta, 0, 0)
//   straight: (t + v dt h(theta), theta, v, 0)
//   arc:      (t + v dt [A h(theta) + B h'(theta)], theta + omega dt, v, omega)
//             with psi = omega dt, A = sin(psi)/psi, B = (1 - cos psi)/psi and
//             h'(theta) = dh/dtheta = (-sin, 0, -cos); A, B and their
//             derivatives use Taylor series for |psi| < 1e-3 (exact limit at
//             psi = 0: the straight model).
// Selected from the previous state's velocities: |v| < eps_v -> standing,
// else |omega| < eps_omega -> straight, else arc.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

#include "libsamp/core/pose.h"

namespace samp {

enum class MotionModel { kStanding = 0, kStraight = 1, kArc = 2 };
const char* MotionModelName(MotionModel model);

// WrapAngle, Heading, YawOfDirection, WorldFromObject and ObjectFromWorld: core/pose.h.

struct MotionNoise {
  // Velocity noise per second (random walk): sigma_v = speed_noise * sqrt(dt), m/s;
  // sigma_omega = yaw_rate_noise * sqrt(dt), rad/s. Propagated to the pose to first order.
  double speed_noise = 1.0;
  double yaw_rate_noise = 0.3;
  // Constant terms of Sigma (standard deviations) added to every model.
  double sigma_position = 0.05;  // horizontal (world x, z), m
  double sigma_height = 0.05;    // vertical (world y), m
  double sigma_yaw = 0.02;       // rad
  double sigma_speed = 0.2;      // m/s
  double sigma_yaw_rate = 0.05;  // rad/s
  void Check() const;  // throws samp::Error naming the field
};

// Chooses the model from the previous state's velocities.
MotionModel SelectMotionModel(double speed, double yaw_rate, double eps_speed, double eps_yaw_rate);

// Prediction g(xi) of the next state. pose = (tx, ty, tz, theta), velocity =
// (v, omega). Optional Jacobians (row-major 6x4 and 6x2) of the 6-vector
// (t, theta, v, omega) predicted with respect to pose and velocity.
void PredictMotion(MotionModel model, const double* pose, const double* velocity, double dt,
                   double* predicted /*6*/, double* d_pose /*6x4*/, double* d_velocity /*6x2*/);

// Sigma = G Q G^T + diag(constant terms)^2 with G = d g / d(v, omega) at the
// state and Q = diag(sigma_v^2, sigma_omega^2) (see MotionNoise).
Eigen::Matrix<double, 6, 6> MotionCovariance(MotionModel model, const double* pose,
                                             const double* velocity, double dt,
                                             const MotionNoise& noise);

// Upper-triangular square root of the information: L with L^T L = Sigma^-1.
Eigen::Matrix<double, 6, 6> SqrtInformation(const Eigen::Matrix<double, 6, 6>& covariance);

}  // namespace samp
