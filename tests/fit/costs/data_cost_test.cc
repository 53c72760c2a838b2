// The data terms' shared parts: the robustifiers, input checks and the factory.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "libsamp/core/error.h"
#include "libsamp/core/pose.h"
#include "libsamp/fit/costs/data_cost.h"
#include "libsamp/fit/costs/disparity.h"
#include "libsamp/fit/costs/point_sdf.h"
#include "libsamp/fit/costs/ray_depth.h"
#include "tests/fit/cost_test_util.h"

namespace samp {
namespace {

using testing::ExpectJacobiansMatch;
const ShapeLookup& Lookup() { return testing::CostLookup(); }

TEST(DataCost, HuberPsi) {
  double d;
  EXPECT_DOUBLE_EQ(HuberPsi(0.5, 1.0, &d), 0.5);
  EXPECT_DOUBLE_EQ(d, 1.0);
  // psi^2 = 2 k |s| - k^2 outside.
  EXPECT_NEAR(HuberPsi(3.0, 1.0, &d), std::sqrt(5.0), 1e-15);
  EXPECT_NEAR(d, 1.0 / std::sqrt(5.0), 1e-15);
  EXPECT_NEAR(HuberPsi(-3.0, 1.0, &d), -std::sqrt(5.0), 1e-15);
  // C^1 at the threshold.
  double d1, d2;
  EXPECT_NEAR(HuberPsi(1.0 - 1e-9, 1.0, &d1), HuberPsi(1.0 + 1e-9, 1.0, &d2), 1e-8);
  EXPECT_NEAR(d1, d2, 1e-8);
}

TEST(DataCost, MixturePsi) {
  // psi^2 = rho = -2 log((exp(-s^2/2) + c) / (1 + c)), c = exp(-s0^2/2).
  const double s0 = 3.0, c = std::exp(-4.5);
  for (double s : {-7.0, -3.0, -1.0, -1e-6, 0.0, 1e-8, 0.3, 2.0, 3.0, 10.0}) {
    double d;
    const double psi = MixturePsi(s, s0, &d);
    const double rho = -2.0 * std::log((std::exp(-0.5 * s * s) + c) / (1.0 + c));
    EXPECT_NEAR(psi * psi, rho, 1e-12 * std::max(1.0, rho)) << s;
    EXPECT_GE(psi * s, 0.0);
    const double h = 1e-6;
    if (std::abs(s) > 1e-5) {
      const double numeric = (MixturePsi(s + h, s0, nullptr) - MixturePsi(s - h, s0, nullptr)) / (2 * h);
      EXPECT_NEAR(d, numeric, 1e-6 * std::max(1.0, std::abs(numeric))) << s;
    } else {
      EXPECT_NEAR(d, 1.0 / std::sqrt(1.0 + c), 1e-9);
    }
  }
  // Bounded: clutter far from the surface adds at most rho_max.
  const double rho_max = -2.0 * std::log(c / (1.0 + c));
  EXPECT_NEAR(std::pow(MixturePsi(50.0, s0, nullptr), 2), rho_max, 1e-9);
  EXPECT_LT(std::pow(MixturePsi(2.0, s0, nullptr), 2), 0.5 * rho_max);
}

TEST(DataCost, MixturePsiRowsAgreesWithOneAtATime) {
  // The rows' psi and d psi / ds equal MixturePsiWithC's to a few ulp (bit
  // for bit without AVX2), for every count (the last group of four padded),
  // zero, tiny and huge |s|, both signs.
  const double c = std::exp(-4.5);
  std::mt19937 rng(5);
  std::normal_distribution<double> normal(0.0, 1.5);
  std::vector<double> s = {0.0, 1e-300, -1e-12, 3e-8, -1e-4, 0.5, -1.0, 2.9, -3.0, 3.1, 8.0, -40.0, 1e3, -1e8};
  for (int k = 0; k < 200; ++k) s.push_back(k % 7 == 0 ? 8.0 * normal(rng) : normal(rng));
  for (size_t first = 0; first < 4; ++first) {
    for (int n = 0; n <= int(s.size() - first); n += (n < 12 ? 1 : 37)) {
      std::vector<double> psi(size_t(n) + 1, -7.0), d_psi(size_t(n) + 1, -7.0);
      MixturePsiRows(s.data() + first, n, c, psi.data(), d_psi.data());
      EXPECT_EQ(psi[size_t(n)], -7.0) << "wrote past the rows";
      EXPECT_EQ(d_psi[size_t(n)], -7.0) << "wrote past the rows";
      for (int k = 0; k < n; ++k) {
        const double v = s[first + size_t(k)];
        double d;
        const double expected = MixturePsiWithC(v, c, &d);
        const double tolerance = MixturePsiRowsVectorised() ? 1e-14 : 0.0;
        EXPECT_NEAR(psi[size_t(k)], expected, tolerance * std::abs(expected)) << v;
        EXPECT_NEAR(d_psi[size_t(k)], d, tolerance * std::abs(d) + 1e-300) << v;
        EXPECT_GE(psi[size_t(k)] * v, 0.0) << v;
      }
    }
  }
}

TEST(DataCost, RejectsBadInput) {
  const ShapeLookup& lookup = Lookup();
  EXPECT_THROW(PointSdfCost(&lookup, {}, {}, testing::HuberOptions(1.0, 1.0)), Error);
  EXPECT_THROW(PointSdfCost(&lookup, {Eigen::Vector3d(0, 0, 1)}, {0.0}, testing::HuberOptions(1.0, 1.0)), Error);
  EXPECT_THROW(PointSdfCost(&lookup, {Eigen::Vector3d(NAN, 0, 1)}, {0.1}, testing::HuberOptions(1.0, 1.0)), Error);
}

TEST(DataCost, MakeDataCostSelectsTheTerm) {
  const ShapeLookup& lookup = Lookup();
  DataCostOptions options;
  options.camera_in_world = Eigen::Vector3d(0.0, 0.0, 0.0);
  options.focal_px = 700.0;
  const std::vector<Eigen::Vector3d> points = {Eigen::Vector3d(4.0, 1.6, 15.0)};
  options.term = DataTerm::kPaper;
  EXPECT_NE(dynamic_cast<PointSdfCost*>(MakeDataCost(&lookup, points, {0.1}, options).get()), nullptr);
  options.term = DataTerm::kRayDepth;
  EXPECT_NE(dynamic_cast<RayDepthCost*>(MakeDataCost(&lookup, points, {0.1}, options).get()), nullptr);
  options.term = DataTerm::kDisparity;
  EXPECT_NE(dynamic_cast<DisparityCost*>(MakeDataCost(&lookup, points, {0.1}, options).get()), nullptr);
}

}  // namespace
}  // namespace samp
