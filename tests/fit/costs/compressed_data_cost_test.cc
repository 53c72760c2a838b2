// The compressed data block (compressed_data_cost.h): the same cost,
// gradient and Gauss-Newton matrix as the full block, and its cache.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "libsamp/core/error.h"
#include "libsamp/core/pose.h"
#include "libsamp/fit/costs/compressed_data_cost.h"
#include "tests/fit/cost_test_util.h"

namespace samp {
namespace {

using testing::ExpectJacobiansMatch;
const ShapeLookup& Lookup() { return testing::CostLookup(); }

TEST(CompressedDataCost, SameCostGradientAndGaussNewtonMatrix) {
  const ShapeLookup& lookup = Lookup();
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::VectorXd z_true = 0.5 * lookup.sigmas();
  const auto surface = testing::SampleSurface(lookup, z_true, 300, &rng);
  for (const DataTerm term : {DataTerm::kPaper, DataTerm::kRayDepth, DataTerm::kDisparity})
  for (double offset : {0.05, 0.5, 4.0}) {  // last: many points outside the grid
    const bool ray = term != DataTerm::kPaper;
    DataCostOptions options;
    options.weight = 0.2;
    options.term = term;
    options.focal_px = 700.0;
    const Eigen::Isometry3d world_from_object = WorldFromObject(Eigen::Vector3d(3, 1.6, 12), kPi - 0.01);
    std::vector<Eigen::Vector3d> points;
    std::vector<double> sigmas;
    for (const auto& p : surface) {
      points.push_back(world_from_object * (p + offset * testing::DrawVector(n, rng)));
      sigmas.push_back(0.1);
    }
    const std::unique_ptr<DataCost> full_cost = MakeDataCost(&lookup, points, sigmas, options);
    const DataCost& full = *full_cost;
    CompressedDataCost compressed(MakeDataCost(&lookup, points, sigmas, options));
    ASSERT_EQ(compressed.num_residuals(), 10);
    Eigen::VectorXd z = -0.2 * lookup.sigmas();
    double pose[4] = {3.1, 1.55, 12.05, -kPi + 0.02};
    const double* params[2] = {z.data(), pose};
    using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    const int n_full = full.num_residuals();
    Eigen::VectorXd rf(n_full), rc(10), rc_cost(10);
    RowMatrix jzf(n_full, 5), jpf(n_full, 4), jzc(10, 5), jpc(10, 4);
    double* jf[2] = {jzf.data(), jpf.data()};
    double* jc[2] = {jzc.data(), jpc.data()};
    ASSERT_TRUE(full.Evaluate(params, rf.data(), jf));
    ASSERT_TRUE(compressed.Evaluate(params, rc.data(), jc));
    ASSERT_TRUE(compressed.Evaluate(params, rc_cost.data(), nullptr));
    RowMatrix af(n_full, 9), ac(10, 9);
    af << jzf, jpf;
    ac << jzc, jpc;
    const double scale = std::max(1.0, rf.squaredNorm());
    EXPECT_NEAR(rc.squaredNorm(), rf.squaredNorm(), 1e-9 * scale) << "offset " << offset << " ray " << ray;
    EXPECT_NEAR(rc_cost.squaredNorm(), rf.squaredNorm(), 1e-9 * scale);
    const Eigen::VectorXd gf = af.transpose() * rf, gc = ac.transpose() * rc;
    EXPECT_LT((gf - gc).cwiseAbs().maxCoeff(), 1e-8 * std::max(1.0, gf.cwiseAbs().maxCoeff()));
    const Eigen::MatrixXd hf = af.transpose() * af, hc = ac.transpose() * ac;
    EXPECT_LT((hf - hc).cwiseAbs().maxCoeff(), 1e-8 * std::max(1.0, hf.cwiseAbs().maxCoeff()));
    // The linearised cost agrees for an arbitrary step.
    Eigen::VectorXd d(9);
    d << 0.1, -0.2, 0.3, 0.0, 0.05, 0.02, -0.01, 0.03, 0.01;
    EXPECT_NEAR((af * d + rf).squaredNorm(), (ac * d + rc).squaredNorm(), 1e-8 * scale);
  }
}

TEST(CompressedDataCost, CachedLinearisationFollowsTheParameters) {
  // Every evaluation linearises and keeps the result for its parameters: a
  // cost-only call followed by a Jacobian call at the same parameters, and
  // calls alternating between parameters, must give what a fresh block gives.
  const ShapeLookup& lookup = Lookup();
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0.0, 1.0);
  const auto surface = testing::SampleSurface(lookup, 0.5 * lookup.sigmas(), 200, &rng);
  const Eigen::Isometry3d world_from_object = WorldFromObject(Eigen::Vector3d(3, 1.6, 12), 0.3);
  std::vector<Eigen::Vector3d> points;
  for (const auto& p : surface) points.push_back(world_from_object * (p + 0.05 * testing::DrawVector(n, rng)));
  const std::vector<double> sigmas(points.size(), 0.1);
  using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  struct Result {
    Eigen::VectorXd r = Eigen::VectorXd(10);
    RowMatrix jz = RowMatrix(10, 5), jp = RowMatrix(10, 4);
  };
  auto evaluate = [](const CompressedDataCost& cost, const Eigen::VectorXd& z, const double* pose, bool jacobians) {
    Result out;
    const double* params[2] = {z.data(), pose};
    double* j[2] = {out.jz.data(), out.jp.data()};
    EXPECT_TRUE(cost.Evaluate(params, out.r.data(), jacobians ? j : nullptr));
    return out;
  };
  const Eigen::VectorXd z1 = 0.2 * lookup.sigmas(), z2 = -0.1 * lookup.sigmas();
  const double pose1[4] = {3.05, 1.6, 12.02, 0.31}, pose2[4] = {2.95, 1.62, 11.97, 0.28};
  const CompressedDataCost fresh1(MakeDataCost(&lookup, points, sigmas, testing::HuberOptions(1.0, 0.5))),
      fresh2(MakeDataCost(&lookup, points, sigmas, testing::HuberOptions(1.0, 0.5)));
  const Result expected1 = evaluate(fresh1, z1, pose1, true), expected2 = evaluate(fresh2, z2, pose2, true);
  const CompressedDataCost cost(MakeDataCost(&lookup, points, sigmas, testing::HuberOptions(1.0, 0.5)));
  const Result cost_only = evaluate(cost, z1, pose1, false);
  EXPECT_EQ(cost_only.r, expected1.r);
  const Result with_jacobians = evaluate(cost, z1, pose1, true);
  EXPECT_EQ(with_jacobians.r, expected1.r);
  EXPECT_EQ(with_jacobians.jz, expected1.jz);
  EXPECT_EQ(with_jacobians.jp, expected1.jp);
  const Result other = evaluate(cost, z2, pose2, true);
  EXPECT_EQ(other.r, expected2.r);
  EXPECT_EQ(other.jp, expected2.jp);
  EXPECT_NE(other.r, expected1.r);
  const double pose1_moved[4] = {pose1[0], pose1[1], pose1[2], pose1[3] + 1e-9};
  EXPECT_NE(evaluate(cost, z1, pose1_moved, false).r, expected1.r) << "a changed pose must not hit the cache";
  EXPECT_EQ(evaluate(cost, z1, pose1, true).jz, expected1.jz);
}

}  // namespace
}  // namespace samp
