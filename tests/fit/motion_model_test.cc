#include "libsamp/fit/motion_model.h"

#include <gtest/gtest.h>

#include <cmath>

namespace samp {
namespace {

// Central differences of PredictMotion with respect to pose and velocity.
void NumericJacobians(MotionModel model, const double* pose, const double* velocity, double dt,
                      Eigen::Matrix<double, 6, 4>* jp, Eigen::Matrix<double, 6, 2>* jv) {
  const double h = 1e-6;
  for (int k = 0; k < 4; ++k) {
    double p1[4], p2[4], a[6], b[6];
    std::copy(pose, pose + 4, p1);
    std::copy(pose, pose + 4, p2);
    p1[k] += h;
    p2[k] -= h;
    PredictMotion(model, p1, velocity, dt, a, nullptr, nullptr);
    PredictMotion(model, p2, velocity, dt, b, nullptr, nullptr);
    for (int r = 0; r < 6; ++r) (*jp)(r, k) = (a[r] - b[r]) / (2 * h);
  }
  for (int k = 0; k < 2; ++k) {
    double v1[2] = {velocity[0], velocity[1]}, v2[2] = {velocity[0], velocity[1]}, a[6], b[6];
    v1[k] += h;
    v2[k] -= h;
    PredictMotion(model, pose, v1, dt, a, nullptr, nullptr);
    PredictMotion(model, pose, v2, dt, b, nullptr, nullptr);
    for (int r = 0; r < 6; ++r) (*jv)(r, k) = (a[r] - b[r]) / (2 * h);
  }
}

TEST(MotionModel, WrapAngle) {
  EXPECT_NEAR(WrapAngle(0.1), 0.1, 1e-15);
  EXPECT_NEAR(WrapAngle(M_PI), M_PI, 1e-15);
  EXPECT_NEAR(WrapAngle(-M_PI), M_PI, 1e-15);
  EXPECT_NEAR(WrapAngle(3 * M_PI + 0.2), -M_PI + 0.2, 1e-12);
  EXPECT_NEAR(WrapAngle(-M_PI - 0.1), M_PI - 0.1, 1e-12);
  EXPECT_NEAR(WrapAngle(2 * M_PI - 0.3), -0.3, 1e-12);
}

TEST(MotionModel, Selection) {
  EXPECT_EQ(SelectMotionModel(0.1, 0.5, 0.5, 0.05), MotionModel::kStanding);
  EXPECT_EQ(SelectMotionModel(5.0, 0.01, 0.5, 0.05), MotionModel::kStraight);
  EXPECT_EQ(SelectMotionModel(-5.0, -0.2, 0.5, 0.05), MotionModel::kArc);
}

TEST(MotionModel, HeadingMatchesObjectFrame) {
  for (double yaw : {0.0, 0.7, -2.0, M_PI}) {
    const Eigen::Isometry3d w = WorldFromObject(Eigen::Vector3d(1, 2, 3), yaw);
    EXPECT_LT((w.linear() * Eigen::Vector3d::UnitX() - Heading(yaw)).norm(), 1e-12);
    EXPECT_NEAR(WrapAngle(YawOfDirection(Heading(yaw)) - yaw), 0.0, 1e-12);
    EXPECT_TRUE((ObjectFromWorld(Eigen::Vector3d(1, 2, 3), yaw) * w).matrix().isIdentity(1e-12));
  }
}

TEST(MotionModel, ArcIsExactCircle) {
  // A car on a circle of radius r = v / omega: after dt it is on the circle
  // and its heading is tangent.
  const double v = 8.0, omega = 0.4, dt = 0.1, yaw = 0.3;
  const double pose[4] = {1.0, 0.5, -2.0, yaw}, vel[2] = {v, omega};
  double next[6];
  PredictMotion(MotionModel::kArc, pose, vel, dt, next, nullptr, nullptr);
  // Centre of rotation: to the left of the heading (object z axis, world R_y * e_z).
  const Eigen::Vector3d left = WorldFromObject(Eigen::Vector3d::Zero(), yaw).linear() * Eigen::Vector3d::UnitZ();
  // Turning with positive yaw rate turns the heading towards... whichever
  // side: the centre is where distances to both positions equal v / |omega|.
  const Eigen::Vector3d p0(pose[0], pose[1], pose[2]), p1(next[0], next[1], next[2]);
  const double r = v / omega;
  const Eigen::Vector3d c1 = p0 + r * left, c2 = p0 - r * left;
  const double e1 = std::abs((p1 - c1).norm() - r), e2 = std::abs((p1 - c2).norm() - r);
  EXPECT_LT(std::min(e1, e2), 1e-9);
  EXPECT_NEAR(next[3], yaw + omega * dt, 1e-12);
  // Arc length equals v dt: chord = 2 r sin(psi/2).
  EXPECT_NEAR((p1 - p0).norm(), 2 * r * std::sin(omega * dt / 2), 1e-9);
  // Heading at the end is tangent to the circle.
  const Eigen::Vector3d centre = e1 < e2 ? c1 : c2;
  EXPECT_NEAR(Heading(next[3]).dot(p1 - centre), 0.0, 1e-9);
}

TEST(MotionModel, ArcContinuousAsYawRateVanishes) {
  const double pose[4] = {0.0, 0.0, 0.0, 1.2}, dt = 0.1;
  double straight[6];
  const double vel0[2] = {10.0, 0.0};
  PredictMotion(MotionModel::kStraight, pose, vel0, dt, straight, nullptr, nullptr);
  for (double omega : {0.0, 1e-12, -1e-9, 1e-6, 5e-3, 9.9e-3, 1.01e-2}) {
    const double vel[2] = {10.0, omega};
    double arc[6];
    PredictMotion(MotionModel::kArc, pose, vel, dt, arc, nullptr, nullptr);
    for (int k = 0; k < 3; ++k) {
      EXPECT_TRUE(std::isfinite(arc[k]));
      EXPECT_NEAR(arc[k], straight[k], 0.5 * std::abs(omega) * dt * 10.0 * dt + 1e-12);
    }
  }
  // Series and closed form agree around the switch |psi| = 1e-3.
  double below[6], above[6];
  const double vb[2] = {10.0, 0.999e-2}, va[2] = {10.0, 1.001e-2};
  PredictMotion(MotionModel::kArc, pose, vb, dt, below, nullptr, nullptr);
  PredictMotion(MotionModel::kArc, pose, va, dt, above, nullptr, nullptr);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(below[k], above[k], 1e-5);
}

TEST(MotionModel, JacobiansMatchCentralDifferences) {
  const MotionModel models[] = {MotionModel::kStanding, MotionModel::kStraight, MotionModel::kArc};
  const double yaws[] = {0.0, 0.5, M_PI - 1e-7, -M_PI + 1e-7, 2.5};
  const double omegas[] = {0.0, 1e-9, 2e-4, 0.3, -1.2};
  for (MotionModel model : models) {
    for (double yaw : yaws) {
      for (double omega : omegas) {
        const double pose[4] = {3.0, -0.5, 12.0, yaw}, vel[2] = {7.5, omega};
        double pred[6];
        Eigen::Matrix<double, 6, 4, Eigen::RowMajor> jp;
        Eigen::Matrix<double, 6, 2, Eigen::RowMajor> jv;
        PredictMotion(model, pose, vel, 0.1, pred, jp.data(), jv.data());
        Eigen::Matrix<double, 6, 4> np;
        Eigen::Matrix<double, 6, 2> nv;
        NumericJacobians(model, pose, vel, 0.1, &np, &nv);
        EXPECT_LT((jp - np).cwiseAbs().maxCoeff(), 1e-6)
            << MotionModelName(model) << " yaw " << yaw << " omega " << omega;
        EXPECT_LT((jv - nv).cwiseAbs().maxCoeff(), 1e-6)
            << MotionModelName(model) << " yaw " << yaw << " omega " << omega;
      }
    }
  }
}

TEST(MotionModel, CovariancePropagatesVelocityNoise) {
  MotionNoise noise;
  const double pose[4] = {0, 0, 0, 0.0}, vel[2] = {10.0, 0.2}, dt = 0.1;
  const auto standing = MotionCovariance(MotionModel::kStanding, pose, vel, dt, noise);
  EXPECT_NEAR(standing(0, 0), noise.sigma_position * noise.sigma_position, 1e-15);
  EXPECT_NEAR(standing(0, 2), 0.0, 1e-15);
  const auto straight = MotionCovariance(MotionModel::kStraight, pose, vel, dt, noise);
  // Heading along world x: along-track variance grows by dt^2 sigma_v^2.
  EXPECT_NEAR(straight(0, 0) - standing(0, 0), dt * dt * noise.speed_noise * noise.speed_noise * dt, 1e-12);
  EXPECT_NEAR(straight(2, 2), standing(2, 2), 1e-12);
  const auto arc = MotionCovariance(MotionModel::kArc, pose, vel, dt, noise);
  EXPECT_GT(arc(2, 2), standing(2, 2));  // yaw-rate noise moves the car sideways
  EXPECT_GT(arc(3, 3), standing(3, 3));
  EXPECT_NEAR(arc(3, 5), dt * noise.yaw_rate_noise * noise.yaw_rate_noise * dt, 1e-12);
  const auto l = SqrtInformation(arc);
  EXPECT_LT(((l.transpose() * l) * arc - Eigen::Matrix<double, 6, 6>::Identity()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT(l.triangularView<Eigen::StrictlyLower>().toDenseMatrix().cwiseAbs().maxCoeff(), 1e-15);
}

}  // namespace
}  // namespace samp
