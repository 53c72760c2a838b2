// The evaluation measures on hand-made point sets with known answers.
#include "libsamp/eval/metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "libsamp/core/error.h"

namespace samp {
namespace {

// 11 x 11 points on the unit square (spacing 0.1 m) at height z.
std::vector<Eigen::Vector3d> Square(double z, double max_x = 1.0) {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i <= 10; ++i) {
    for (int j = 0; j <= 10; ++j) {
      if (0.1 * i <= max_x + 1e-9) points.emplace_back(0.1 * i, 0.1 * j, z);
    }
  }
  return points;
}

TEST(RadiusNearestNeighbor, MatchesBruteForce) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Eigen::Vector3d> reference(2000), queries(500);
  for (auto& p : reference) p = Eigen::Vector3d(u(rng), u(rng), 0.2 * u(rng));
  for (auto& q : queries) q = Eigen::Vector3d(1.3 * u(rng), 1.3 * u(rng), u(rng));
  const double max_radius = 0.3;
  const RadiusNearestNeighbor index(reference, max_radius);
  int within = 0;
  for (const auto& q : queries) {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& p : reference) best = std::min(best, (p - q).norm());
    const double got = index.Distance(q);
    if (best <= max_radius) {
      ++within;
      EXPECT_NEAR(got, best, 1e-12);
    } else {
      EXPECT_TRUE(std::isinf(got)) << "query beyond the radius must give inf, got " << got;
    }
  }
  EXPECT_GT(within, 100);
  EXPECT_LT(within, 500);
}

TEST(RadiusNearestNeighbor, NegativeCoordinatesAndEmptySet) {
  const RadiusNearestNeighbor index({Eigen::Vector3d(-0.05, -0.05, -0.05)}, 0.2);
  EXPECT_NEAR(index.Distance(Eigen::Vector3d(0.05, -0.05, -0.05)), 0.1, 1e-12);
  EXPECT_TRUE(std::isinf(index.Distance(Eigen::Vector3d(0.5, 0, 0))));
  const RadiusNearestNeighbor empty({}, 0.2);
  EXPECT_TRUE(std::isinf(empty.Distance(Eigen::Vector3d::Zero())));
  EXPECT_THROW(RadiusNearestNeighbor({}, 0.0), Error);
}

TEST(ShapeScores, ShiftedCopy) {
  // Every estimated point is exactly 0.15 m from its true point.
  const ShapeComparison c = CompareShapes(Square(0.15), Square(0.0), 0.5);
  const ShapeScores below = c.At(0.1);
  EXPECT_DOUBLE_EQ(below.accuracy, 0.0);
  EXPECT_DOUBLE_EQ(below.completeness, 0.0);
  EXPECT_DOUBLE_EQ(below.f1, 0.0);
  const ShapeScores above = c.At(0.2);
  EXPECT_DOUBLE_EQ(above.accuracy, 1.0);
  EXPECT_DOUBLE_EQ(above.completeness, 1.0);
  EXPECT_DOUBLE_EQ(above.f1, 1.0);
}

TEST(ShapeScores, PartialWithOutliers) {
  // Estimate: the left half (x <= 0.5: 66 of 121 points) exactly, plus 10 outliers 5 m away.
  std::vector<Eigen::Vector3d> estimated = Square(0.0, 0.5);
  ASSERT_EQ(estimated.size(), 66u);
  for (int i = 0; i < 10; ++i) estimated.emplace_back(5.0 + i, 0.0, 0.0);
  const ShapeComparison c = CompareShapes(estimated, Square(0.0), 0.5);
  const ShapeScores s = c.At(0.05);
  EXPECT_DOUBLE_EQ(s.accuracy, 66.0 / 76.0);
  EXPECT_DOUBLE_EQ(s.completeness, 66.0 / 121.0);
  EXPECT_NEAR(s.f1, 2.0 * (66.0 / 76.0) * (66.0 / 121.0) / (66.0 / 76.0 + 66.0 / 121.0), 1e-12);
  // At tau = 0.1 (+ rounding) the column x = 0.6 is also within reach of x = 0.5.
  const ShapeScores t = c.At(0.1 + 1e-9);
  EXPECT_DOUBLE_EQ(t.completeness, 77.0 / 121.0);
  EXPECT_DOUBLE_EQ(t.accuracy, 66.0 / 76.0);
  EXPECT_THROW(c.At(0.6), Error);
}

TEST(ShapeScores, EmptySets) {
  const ShapeComparison no_estimate = CompareShapes({}, Square(0.0), 0.5);
  EXPECT_DOUBLE_EQ(no_estimate.At(0.2).accuracy, 0.0);
  EXPECT_DOUBLE_EQ(no_estimate.At(0.2).completeness, 0.0);
  EXPECT_DOUBLE_EQ(no_estimate.At(0.2).f1, 0.0);
  const ShapeComparison no_truth = CompareShapes(Square(0.0), {}, 0.5);
  EXPECT_DOUBLE_EQ(no_truth.At(0.2).f1, 0.0);
}

TEST(PoseErrors, YawWrapsAndFlipsCount) {
  constexpr double kPi = 3.14159265358979323846;
  EXPECT_NEAR(YawErrorDeg(0.1, -0.1), 0.2 * 180.0 / kPi, 1e-9);
  EXPECT_NEAR(YawErrorDeg(kPi - 0.05, -kPi + 0.05), 0.1 * 180.0 / kPi, 1e-9);
  EXPECT_NEAR(YawErrorDeg(0.0, kPi), 180.0, 1e-9);
  EXPECT_NEAR(YawErrorDeg(0.3, 0.3 + kPi), 180.0, 1e-9);
  EXPECT_NEAR(YawErrorDeg(3 * kPi, 0.0), 180.0, 1e-9);
  EXPECT_NEAR(YawErrorDeg(0.2, 0.2 + 4 * kPi), 0.0, 1e-9);
}

TEST(PoseErrors, MeanAndMedian) {
  EXPECT_DOUBLE_EQ(Mean({}), 0.0);
  EXPECT_DOUBLE_EQ(Median({}), 0.0);
  EXPECT_DOUBLE_EQ(Median({3.0, 1.0, 2.0}), 2.0);
  EXPECT_DOUBLE_EQ(Median({4.0, 1.0, 3.0, 2.0}), 2.5);
  EXPECT_DOUBLE_EQ(Mean({1.0, 2.0, 6.0}), 3.0);
}

}  // namespace
}  // namespace samp
