#include "libsamp/fit/motion_model.h"

#include <cmath>

#include "libsamp/core/error.h"

namespace samp {

const char* MotionModelName(MotionModel model) {
  switch (model) {
    case MotionModel::kStanding: return "standing";
    case MotionModel::kStraight: return "straight";
    case MotionModel::kArc: return "arc";
  }
  return "unknown";
}

MotionModel SelectMotionModel(double speed, double yaw_rate, double eps_speed, double eps_yaw_rate) {
  if (std::abs(speed) < eps_speed) return MotionModel::kStanding;
  if (std::abs(yaw_rate) < eps_yaw_rate) return MotionModel::kStraight;
  return MotionModel::kArc;
}

namespace {

// A(psi) = sin(psi)/psi, B(psi) = (1 - cos psi)/psi and their derivatives.
void ArcCoefficients(double psi, double* a, double* b, double* da, double* db) {
  if (std::abs(psi) < 1e-3) {
    const double p2 = psi * psi;
    *a = 1.0 - p2 / 6.0 + p2 * p2 / 120.0;
    *b = psi * (0.5 - p2 / 24.0 + p2 * p2 / 720.0);
    *da = psi * (-1.0 / 3.0 + p2 / 30.0);
    *db = 0.5 - p2 / 8.0 + p2 * p2 / 144.0;
    return;
  }
  const double s = std::sin(psi), c = std::cos(psi);
  *a = s / psi;
  *b = (1.0 - c) / psi;
  *da = (psi * c - s) / (psi * psi);
  *db = (psi * s - (1.0 - c)) / (psi * psi);
}

}  // namespace

void PredictMotion(MotionModel model, const double* pose, const double* velocity, double dt,
                   double* predicted, double* d_pose, double* d_velocity) {
  const double theta = pose[3], v = velocity[0], omega = velocity[1];
  const double c = std::cos(theta), s = std::sin(theta);
  // h = (c, 0, -s), h' = (-s, 0, -c), h'' = -h.
  Eigen::Map<Eigen::Matrix<double, 6, 4, Eigen::RowMajor>> jp(d_pose ? d_pose : nullptr);
  Eigen::Map<Eigen::Matrix<double, 6, 2, Eigen::RowMajor>> jv(d_velocity ? d_velocity : nullptr);
  if (d_pose) jp.setZero();
  if (d_velocity) jv.setZero();
  for (int k = 0; k < 4; ++k) predicted[k] = pose[k];
  if (d_pose) jp.topLeftCorner<4, 4>().setIdentity();
  switch (model) {
    case MotionModel::kStanding:
      predicted[4] = 0.0;
      predicted[5] = 0.0;
      break;
    case MotionModel::kStraight: {
      const double l = v * dt;
      predicted[0] += l * c;
      predicted[2] += -l * s;
      predicted[4] = v;
      predicted[5] = 0.0;
      if (d_pose) {
        jp(0, 3) = -l * s;
        jp(2, 3) = -l * c;
      }
      if (d_velocity) {
        jv(0, 0) = dt * c;
        jv(2, 0) = -dt * s;
        jv(4, 0) = 1.0;
      }
      break;
    }
    case MotionModel::kArc: {
      const double psi = omega * dt, l = v * dt;
      double a, b, da, db;
      ArcCoefficients(psi, &a, &b, &da, &db);
      // delta = l (A h + B h'): x = l (A c - B s), z = l (-A s - B c).
      const double dx = l * (a * c - b * s), dz = l * (-a * s - b * c);
      predicted[0] += dx;
      predicted[2] += dz;
      predicted[3] = theta + psi;
      predicted[4] = v;
      predicted[5] = omega;
      if (d_pose) {
        // d/dtheta: l (A h' + B h'') = l (A h' - B h).
        jp(0, 3) = l * (-a * s - b * c);
        jp(2, 3) = l * (-a * c + b * s);
      }
      if (d_velocity) {
        jv(0, 0) = dt * (a * c - b * s);
        jv(2, 0) = dt * (-a * s - b * c);
        jv(0, 1) = l * dt * (da * c - db * s);
        jv(2, 1) = l * dt * (-da * s - db * c);
        jv(3, 1) = dt;
        jv(4, 0) = 1.0;
        jv(5, 1) = 1.0;
      }
      break;
    }
  }
}

Eigen::Matrix<double, 6, 6> MotionCovariance(MotionModel model, const double* pose,
                                             const double* velocity, double dt,
                                             const MotionNoise& noise) {
  double predicted[6];
  Eigen::Matrix<double, 6, 2, Eigen::RowMajor> g;
  PredictMotion(model, pose, velocity, dt, predicted, nullptr, g.data());
  Eigen::Matrix2d q = Eigen::Matrix2d::Zero();
  q(0, 0) = noise.speed_noise * noise.speed_noise * std::abs(dt);
  q(1, 1) = noise.yaw_rate_noise * noise.yaw_rate_noise * std::abs(dt);
  Eigen::Matrix<double, 6, 6> sigma = g * q * g.transpose();
  Eigen::Matrix<double, 6, 1> constant;
  constant << noise.sigma_position, noise.sigma_height, noise.sigma_position, noise.sigma_yaw,
      noise.sigma_speed, noise.sigma_yaw_rate;
  sigma.diagonal() += constant.cwiseAbs2();
  return sigma;
}

Eigen::Matrix<double, 6, 6> SqrtInformation(const Eigen::Matrix<double, 6, 6>& covariance) {
  const Eigen::Matrix<double, 6, 6> information =
      covariance.llt().solve(Eigen::Matrix<double, 6, 6>::Identity());
  Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(0.5 * (information + information.transpose()));
  SAMP_CHECK(llt.info() == Eigen::Success) << "motion covariance is not positive definite";
  // information = L L^T; sqrt information = L^T (upper), (L^T)^T L^T = information.
  return llt.matrixL().transpose();
}

}  // namespace samp
