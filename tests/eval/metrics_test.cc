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


// CLEAR-MOT on a hand-made sequence: car 0 is tracked by track 7, lost for a
// frame, then continues as track 8 (a fragment: one ID switch, one FRAG);
// car 1 is tracked by track 9 throughout, with a false positive (track 20) in
// frame 2 and a box beside an ignored (barely visible) car 2.
TEST(ClearMot, FragmentSwitchAndFalsePositive) {
  std::vector<TrackedBox> truth, output;
  for (int f = 0; f < 6; ++f) {
    truth.push_back({f, 0, Eigen::Vector3d(-3.0 + 0.5 * f, 1.6, 20.0), false});
    truth.push_back({f, 1, Eigen::Vector3d(3.0, 1.6, 30.0 - f), false});
    if (f != 2) output.push_back({f, f < 2 ? 7 : 8, Eigen::Vector3d(-3.0 + 0.5 * f + 0.3, 1.6, 20.5), false});
    output.push_back({f, 9, Eigen::Vector3d(3.2, 1.6, 30.0 - f - 0.8), false});
  }
  output.push_back({2, 20, Eigen::Vector3d(-8.0, 1.6, 12.0), false});  // nothing there
  truth.push_back({4, 2, Eigen::Vector3d(9.0, 1.6, 8.0), true});       // too few pixels
  output.push_back({4, 21, Eigen::Vector3d(9.5, 1.6, 8.0), false});
  TrackingCounts counts;
  const std::vector<int> match = MatchTracks(truth, output, 2.0, &counts);
  ASSERT_EQ(match.size(), truth.size());
  EXPECT_EQ(match[4], -1);  // car 0 in frame 2: lost
  EXPECT_EQ(counts.true_cars, 2);
  EXPECT_EQ(counts.true_boxes, 12);
  EXPECT_EQ(counts.matches, 11);
  EXPECT_EQ(counts.misses, 1);
  EXPECT_EQ(counts.false_positives, 1);  // track 20; track 21 sits on the ignored car
  EXPECT_EQ(counts.id_switches, 1);
  EXPECT_EQ(counts.fragmentations, 1);
  EXPECT_EQ(counts.tracks_on_cars, 3);
  EXPECT_DOUBLE_EQ(counts.TracksPerCar(), 1.5);
  EXPECT_EQ(counts.in_main_track, 6 + 3);  // car 0: track 8 has 3 of its 5 matches
  EXPECT_EQ(counts.missed_cars, 0);
  EXPECT_EQ(counts.output_tracks, 5);
  EXPECT_EQ(counts.false_tracks, 1);
  EXPECT_NEAR(counts.Mota(), 1.0 - 3.0 / 12.0, 1e-12);
  EXPECT_GT(counts.Motp(), 0.3);
  EXPECT_LT(counts.Motp(), 0.9);
  // Beyond the distance nothing matches.
  TrackingCounts none;
  MatchTracks(truth, output, 0.1, &none);
  EXPECT_EQ(none.matches, 0);
  EXPECT_EQ(none.missed_cars, 2);
  EXPECT_THROW(MatchTracks(truth, output, 0.0, nullptr), Error);
}

// Two cars crossing: the output swaps their tracks in the middle. A car keeps
// the track it had while that track's box stays within the distance
// (CLEAR-MOT), so the swap costs two ID switches, not more.
TEST(ClearMot, SwapCostsTwoSwitches) {
  std::vector<TrackedBox> truth, output;
  for (int f = 0; f < 8; ++f) {
    const Eigen::Vector3d a(-4.0 + f, 1.6, 20.0), b(4.0 - f, 1.6, 23.0);
    truth.push_back({f, 0, a, false});
    truth.push_back({f, 1, b, false});
    output.push_back({f, f < 4 ? 1 : 2, a, false});
    output.push_back({f, f < 4 ? 2 : 1, b, false});
  }
  TrackingCounts counts;
  MatchTracks(truth, output, 2.0, &counts);
  EXPECT_EQ(counts.matches, 16);
  EXPECT_EQ(counts.id_switches, 2);
  EXPECT_EQ(counts.fragmentations, 0);
  EXPECT_DOUBLE_EQ(counts.TracksPerCar(), 2.0);
  EXPECT_DOUBLE_EQ(counts.MainTrackShare(), 0.5);
  // Boxes without track ids are tracks of their own.
  for (TrackedBox& b : output) b.track_id = -1;
  TrackingCounts untracked;
  MatchTracks(truth, output, 2.0, &untracked);
  EXPECT_EQ(untracked.output_tracks, 16);
  EXPECT_EQ(untracked.id_switches, 14);
}

}  // namespace
}  // namespace samp
