// The priors' and detections' cost functors (costs/motion.h, ground.h,
// detection_position.h, shape_prior.h, detection_size.h): residuals and
// analytic Jacobians against central differences and direct formulas.
#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "libsamp/core/error.h"
#include "libsamp/core/pose.h"
#include "libsamp/data/tracking.h"
#include "libsamp/fit/costs/detection_position.h"
#include "libsamp/fit/costs/detection_size.h"
#include "libsamp/fit/costs/ground.h"
#include "libsamp/fit/costs/motion.h"
#include "libsamp/fit/costs/shape_prior.h"
#include "tests/fit/cost_test_util.h"

namespace samp {
namespace {

using testing::ExpectJacobiansMatch;
const ShapeLookup& Lookup() { return testing::CostLookup(); }

TEST(MotionCost, ResidualWrapsYawAndJacobiansMatch) {
  MotionNoise noise;
  const MotionModel models[] = {MotionModel::kStanding, MotionModel::kStraight, MotionModel::kArc};
  for (MotionModel model : models) {
    for (double omega : {0.0, 1e-8, 0.35}) {
      double prev_pose[4] = {2.0, 1.6, 20.0, kPi - 0.01}, prev_vel[2] = {6.0, omega};
      double pred[6];
      PredictMotion(model, prev_pose, prev_vel, 0.1, pred, nullptr, nullptr);
      // Current yaw on the other side of +-pi: the wrapped difference is small.
      double pose[4] = {pred[0] + 0.1, pred[1], pred[2] - 0.05, WrapAngle(pred[3] + 0.02)};
      double vel[2] = {pred[4] + 0.3, pred[5] - 0.01};
      const auto sigma = MotionCovariance(model, prev_pose, prev_vel, 0.1, noise);
      const auto l = SqrtInformation(sigma);
      MotionCost cost(model, 0.1, l, 0.25);
      double r[6];
      const double* params[4] = {prev_pose, prev_vel, pose, vel};
      ASSERT_TRUE(cost.Evaluate(params, r, nullptr));
      Eigen::Matrix<double, 6, 1> e;
      e << 0.1, 0.0, -0.05, 0.02, 0.3, -0.01;
      const Eigen::Matrix<double, 6, 1> expected = 0.5 * l * e;
      for (int k = 0; k < 6; ++k) EXPECT_NEAR(r[k], expected[k], 1e-9) << MotionModelName(model);
      ExpectJacobiansMatch(cost, {prev_pose, prev_vel, pose, vel}, 1e-6,
                           std::string("motion ") + MotionModelName(model));
    }
  }
}

TEST(GroundCost, ResidualAndJacobian) {
  const Eigen::Vector4d plane = Eigen::Vector4d(0.02, -0.999, 0.03, 1.7).normalized();
  const Eigen::Vector4d unit_plane = plane / plane.head<3>().norm();
  GroundCost cost(unit_plane, 0.1, 0.5);
  double pose[4] = {1.0, 1.2, 10.0, 0.4};
  double r;
  const double* params[1] = {pose};
  ASSERT_TRUE(cost.Evaluate(params, &r, nullptr));
  const double height = unit_plane.head<3>().dot(Eigen::Vector3d(1.0, 1.2, 10.0)) + unit_plane[3];
  EXPECT_NEAR(r, std::sqrt(0.5) * height / 0.1, 1e-12);
  ExpectJacobiansMatch(cost, {pose}, 1e-7, "ground");
}

TEST(DetectionPositionCost, ResidualAndJacobian) {
  // The detector noise model's covariance of a box 30 m away, 25 deg off the
  // optical axis, turned into a world frame yawed by 0.3 rad.
  const Eigen::Vector3d in_camera(30 * std::sin(0.44), 1.6, 30 * std::cos(0.44));
  const Eigen::Matrix3d cov_camera = DetectionCovariance(in_camera, TrackerOptions());
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Matrix3d cov = r * cov_camera * r.transpose();
  const Eigen::Vector3d detected = r * in_camera + Eigen::Vector3d(2, 0, -1);
  // Along the horizontal ray the model's sigma is 0.25 + 0.015 * 30 m = 0.70 m.
  const Eigen::Vector3d ray = Eigen::Vector3d(in_camera.x(), 0, in_camera.z()).normalized();
  EXPECT_NEAR(std::sqrt(ray.dot(cov_camera * ray)), 0.25 + 0.015 * 30.0, 1e-9);
  DetectionPositionCost cost(detected, cov, 0.4);
  double pose[4] = {detected.x() + 0.5, detected.y() - 0.1, detected.z() + 0.7, 1.1};
  double res[3];
  const double* params[1] = {pose};
  ASSERT_TRUE(cost.Evaluate(params, res, nullptr));
  const Eigen::Vector3d d(0.5, -0.1, 0.7);
  // |r|^2 = w (t - p)^T Sigma^-1 (t - p); the yaw does not enter.
  EXPECT_NEAR(Eigen::Map<Eigen::Vector3d>(res).squaredNorm(), 0.4 * d.dot(cov.inverse() * d), 1e-9);
  ExpectJacobiansMatch(cost, {pose}, 1e-7, "detection position");
  // A step along the ray costs less than the same step across it.
  double along[4] = {detected.x(), detected.y(), detected.z(), 0}, across[4] = {detected.x(), detected.y(), detected.z(), 0};
  const Eigen::Vector3d ray_world = r * ray, across_world = r * Eigen::Vector3d(ray.z(), 0, -ray.x());
  for (int a = 0; a < 3; ++a) along[a] += 0.5 * ray_world[a], across[a] += 0.5 * across_world[a];
  double r_along[3], r_across[3];
  const double* p_along[1] = {along};
  const double* p_across[1] = {across};
  ASSERT_TRUE(cost.Evaluate(p_along, r_along, nullptr));
  ASSERT_TRUE(cost.Evaluate(p_across, r_across, nullptr));
  EXPECT_LT(Eigen::Map<Eigen::Vector3d>(r_along).norm(), 0.5 * Eigen::Map<Eigen::Vector3d>(r_across).norm());

  // An along-ray bias b (the detector's boxes 0.4 m too far): the pose that
  // costs nothing is the detection minus b along the ray; the Jacobian is the same.
  const Eigen::Vector3d bias = 0.4 * ray_world;
  DetectionPositionCost biased(detected, cov, 0.4, bias);
  double at_truth[4] = {detected.x() - bias.x(), detected.y() - bias.y(), detected.z() - bias.z(), 0.3};
  const double* p_truth[1] = {at_truth};
  double rb[3];
  ASSERT_TRUE(biased.Evaluate(p_truth, rb, nullptr));
  EXPECT_LT(Eigen::Map<Eigen::Vector3d>(rb).norm(), 1e-9);
  ASSERT_TRUE(biased.Evaluate(params, rb, nullptr));
  const Eigen::Vector3d db = d + bias;
  EXPECT_NEAR(Eigen::Map<Eigen::Vector3d>(rb).squaredNorm(), 0.4 * db.dot(cov.inverse() * db), 1e-9);
  ExpectJacobiansMatch(biased, {pose}, 1e-7, "detection position with a bias");
  DetectionPositionCost zero(detected, cov, 0.4, Eigen::Vector3d::Zero());
  double r0[3];
  ASSERT_TRUE(zero.Evaluate(params, r0, nullptr));
  for (int i = 0; i < 3; ++i) EXPECT_EQ(r0[i], res[i]);
}

// The dead zone of a detected position (DeadZoneLoss): rho and its two
// derivatives against finite differences; no cost and no pull within the
// zone; a solve from outside stops at the zone's edge, not at the detection.
TEST(DetectionPositionCost, DeadZoneLoss) {
  const double k = 0.8;
  const DeadZoneLoss loss(k);
  double rho[3];
  for (double s : {0.0, 0.1, 0.63, 0.64}) {
    loss.Evaluate(s, rho);
    EXPECT_EQ(rho[0], 0.0) << s;
    EXPECT_EQ(rho[1], 0.0) << s;
  }
  for (double s : {0.7, 1.0, 4.0, 30.0}) {
    loss.Evaluate(s, rho);
    EXPECT_NEAR(rho[0], (std::sqrt(s) - k) * (std::sqrt(s) - k), 1e-12) << s;
    const double h = 1e-6 * s;
    double lo[3], hi[3];
    loss.Evaluate(s - h, lo);
    loss.Evaluate(s + h, hi);
    EXPECT_NEAR(rho[1], (hi[0] - lo[0]) / (2 * h), 1e-6) << s;
    EXPECT_NEAR(rho[2], (hi[1] - lo[1]) / (2 * h), 1e-5 * std::max(1.0, std::abs(rho[2]))) << s;
    EXPECT_GT(rho[1], 0.0) << s;
    EXPECT_LT(rho[1], 1.0) << s;
  }
  // Far from the zone the loss approaches the plain square: rho' -> 1.
  loss.Evaluate(1e6, rho);
  EXPECT_GT(rho[1], 0.999);

  // One pose and one detection with sigma 0.5 m and weight 0.25: a zone of
  // 1 sigma is k = sqrt(0.25) x 1. From 0.3 m off (inside) nothing moves;
  // from 2 m off the solve stops on the zone's edge, 0.5 m from the detection.
  const Eigen::Vector3d detected(3.0, 1.0, 20.0);
  const Eigen::Matrix3d cov = 0.25 * Eigen::Matrix3d::Identity();
  for (const double start : {0.3, 2.0}) {
    double pose[4] = {detected.x() + start, detected.y(), detected.z(), 0.0};
    const double x0 = pose[0];
    ceres::Problem problem;
    problem.AddResidualBlock(DetectionPositionCost::Create(detected, cov, 0.25), new DeadZoneLoss(std::sqrt(0.25)),
                             pose);
    ceres::Solver::Options options;
    options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    const double offset = pose[0] - detected.x();
    if (start < 0.5) {
      EXPECT_EQ(pose[0], x0);
    } else {
      EXPECT_NEAR(offset, 0.5, 1e-3) << summary.BriefReport();
    }
  }
}

TEST(ShapePriorCost, ResidualAndJacobian) {
  const Eigen::VectorXd sigmas = Eigen::Vector3d(2.0, 1.0, 0.5);
  ShapePriorCost cost(sigmas, 4.0);
  double z[3] = {1.0, -1.0, 0.25};
  double r[3];
  const double* params[1] = {z};
  ASSERT_TRUE(cost.Evaluate(params, r, nullptr));
  EXPECT_NEAR(r[0], 1.0, 1e-15);
  EXPECT_NEAR(r[1], -2.0, 1e-15);
  EXPECT_NEAR(r[2], 1.0, 1e-15);
  ExpectJacobiansMatch(cost, {z}, 1e-7, "shape prior");
}

TEST(DetectionSizeCost, ResidualAndJacobian) {
  const Eigen::VectorXd z0 = Eigen::Vector3d(0.5, -0.2, 0.1);
  Eigen::Matrix<double, 3, Eigen::Dynamic> jacobian(3, 3);
  jacobian << 0.1, 0.0, -0.2, 0.05, 0.3, 0.0, 0.0, -0.1, 0.4;
  const Eigen::Vector3d size0(4.0, 1.5, 1.7), detected(4.3, 1.4, 1.8);
  DetectionSizeCost cost(z0, size0, jacobian, detected, 0.3, 0.25);
  double z[3] = {1.0, -1.0, 0.25};
  double r[3];
  const double* params[1] = {z};
  ASSERT_TRUE(cost.Evaluate(params, r, nullptr));
  const Eigen::Vector3d expected =
      std::sqrt(0.25) / 0.3 * (size0 + jacobian * (Eigen::Map<Eigen::Vector3d>(z) - z0) - detected);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(r[i], expected[i], 1e-14);
  ExpectJacobiansMatch(cost, {z}, 1e-7, "detection size");

  // A box convention b (detected - shape extent): residual = s(z) + b - s_det;
  // the Jacobian does not change. b = 0 gives the same bits as no b.
  const Eigen::Vector3d bias(0.05, -0.02, -0.3);
  DetectionSizeCost biased(z0, size0, jacobian, detected, 0.3, 0.25, bias);
  double rb[3];
  ASSERT_TRUE(biased.Evaluate(params, rb, nullptr));
  const Eigen::Vector3d expected_biased =
      std::sqrt(0.25) / 0.3 * (size0 + jacobian * (Eigen::Map<Eigen::Vector3d>(z) - z0) + bias - detected);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(rb[i], expected_biased[i], 1e-14);
  ExpectJacobiansMatch(biased, {z}, 1e-7, "detection size with a bias");
  // A shape whose extent is the detection minus b costs nothing.
  const Eigen::VectorXd z_at0 = z0;
  DetectionSizeCost exact(z0, detected - bias, jacobian, detected, 0.3, 1.0, bias);
  const double* at0[1] = {z_at0.data()};
  ASSERT_TRUE(exact.Evaluate(at0, rb, nullptr));
  EXPECT_LT(Eigen::Map<Eigen::Vector3d>(rb).norm(), 1e-12);
  DetectionSizeCost zero(z0, size0, jacobian, detected, 0.3, 0.25, Eigen::Vector3d::Zero());
  ASSERT_TRUE(zero.Evaluate(params, rb, nullptr));
  for (int i = 0; i < 3; ++i) EXPECT_EQ(rb[i], r[i]);
}

TEST(ShapeLookup, LinearisedInsideBoxSizePredictsTheBox) {
  // The linearisation about a code predicts the inside box a quarter sigma
  // away better than the box at the code itself does.
  const ShapeLookup& lookup = Lookup();
  const int nr = lookup.num_components();
  Eigen::VectorXd z = Eigen::VectorXd::Zero(nr);
  z[0] = 0.5 * lookup.sigmas()[0];
  ShapeLookup::BoxSizeLinearisation lin;
  ASSERT_TRUE(lookup.LineariseInsideBoxSize(z, 0.5, &lin));
  EXPECT_LT((lin.size - lookup.InsideBox(z).Size()).norm(), 1e-12);
  ASSERT_EQ(lin.jacobian.cols(), nr);
  EXPECT_GT(lin.jacobian.cwiseAbs().maxCoeff(), 0.0);
  for (int i = 0; i < nr; ++i) {
    Eigen::VectorXd dz = Eigen::VectorXd::Zero(nr);
    dz[i] = 0.25 * lookup.sigmas()[i];
    const Eigen::Vector3d actual = lookup.InsideBox(z + dz).Size();
    const Eigen::Vector3d predicted = lin.size + lin.jacobian * dz;
    EXPECT_LE((predicted - actual).cwiseAbs().maxCoeff(),
              std::max(0.02, 0.5 * (lin.size - actual).cwiseAbs().maxCoeff()))
        << "component " << i << ": predicted " << predicted.transpose() << ", actual " << actual.transpose();
  }
  EXPECT_THROW(lookup.LineariseInsideBoxSize(Eigen::VectorXd::Zero(nr + 1), 0.5, &lin), Error);
}

}  // namespace
}  // namespace samp
