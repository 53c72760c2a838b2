// The paper's data term (point_sdf.h): residuals and analytic Jacobians.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "libsamp/core/error.h"
#include "libsamp/core/pose.h"
#include "libsamp/fit/costs/point_sdf.h"
#include "tests/fit/cost_test_util.h"

namespace samp {
namespace {

using testing::ExpectJacobiansMatch;
const ShapeLookup& Lookup() { return testing::CostLookup(); }

struct SdfCase {
  double yaw;
  double huber;
  double offset;  // pushes points away from the surface / out of the grid
};

TEST(PointSdfCost, ResidualAndJacobians) {
  const ShapeLookup& lookup = Lookup();
  std::mt19937 rng(3);
  const Eigen::VectorXd z_true = 0.5 * lookup.sigmas();
  const std::vector<Eigen::Vector3d> surface = testing::SampleSurface(lookup, z_true, 60, &rng);
  ASSERT_EQ(surface.size(), 60u);
  std::normal_distribution<double> n(0.0, 1.0);
  const SdfCase cases[] = {{0.3, 1.0, 0.05},       {kPi - 1e-6, 1.0, 0.1}, {-kPi + 1e-6, 0.5, 0.2},
                           {-1.4, 0.2, 0.3},        {kPi, 1.0, 3.0},        {2.0, 1.0, 5.0}};
  for (const SdfCase& c : cases) {
    const Eigen::Vector3d t(4.0, 1.6, 15.0);
    const Eigen::Isometry3d world_from_object = WorldFromObject(t, c.yaw);
    std::vector<Eigen::Vector3d> points;
    std::vector<double> sigmas;
    for (const auto& p : surface) {
      const Eigen::Vector3d noise = testing::DrawVector(n, rng);
      points.push_back(world_from_object * (p + c.offset * noise));
      sigmas.push_back(0.1 + 0.05 * std::abs(n(rng)));
    }
    const double weight = 1.0 / 7.0;
    PointSdfCost cost(&lookup, points, sigmas, testing::HuberOptions(c.huber, weight));
    Eigen::VectorXd z = 0.3 * lookup.sigmas();
    double pose[4] = {t.x() + 0.05, t.y() - 0.02, t.z() + 0.03, c.yaw + 0.01};
    // Residuals agree with the definition.
    std::vector<double> residuals(points.size());
    const double* params[2] = {z.data(), pose};
    ASSERT_TRUE(cost.Evaluate(params, residuals.data(), nullptr));
    double energy = 0, expected = 0;
    int outside = 0;
    const Eigen::Isometry3d object_from_world =
        ObjectFromWorld(Eigen::Vector3d(pose[0], pose[1], pose[2]), pose[3]);
    for (size_t i = 0; i < points.size(); ++i) {
      energy += residuals[i] * residuals[i];
      const Eigen::Vector3d o = object_from_world * points[i];
      const Eigen::Vector3d lo = lookup.grid().MinCorner(), hi = lookup.grid().MaxCorner();
      outside += ((o.array() < lo.array()) || (o.array() > hi.array())).any();
      const double s = lookup.Evaluate(z, o) / sigmas[i];
      const double rho = std::abs(s) <= c.huber ? s * s : 2 * c.huber * std::abs(s) - c.huber * c.huber;
      expected += weight / points.size() * rho;
    }
    EXPECT_NEAR(energy, expected, 1e-9 * std::max(1.0, expected));
    if (c.offset >= 3.0) {
      EXPECT_GT(outside, 10) << "case must exercise points outside the grid";
    }
    ExpectJacobiansMatch(cost, {z.data(), pose}, 1e-6,
                         "yaw " + std::to_string(c.yaw) + " offset " + std::to_string(c.offset));
  }
}

}  // namespace
}  // namespace samp
