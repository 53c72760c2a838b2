#include "libsamp/data/residual_correlation.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "tests/testing/expect_error.h"

namespace samp {
namespace {

// A polynomial smoother of `q` columns in time over `frames`, weights given.
SmoothedSeries Series(const std::vector<int>& frames, int q, const std::vector<double>& weights) {
  SmoothedSeries s;
  s.frames = frames;
  const int n = static_cast<int>(frames.size());
  s.basis.resize(n, q);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < q; ++k) s.basis(i, k) = std::pow(0.1 * (frames[i] - frames[n / 2]), k);
  s.weights = weights;
  s.residuals.assign(n, 0.0);
  s.used.resize(n);
  for (int i = 0; i < n; ++i) s.used[i] = weights[i] > 0;
  return s;
}

// The smoother's residuals r = (I - H) e of `errors`.
void Smooth(const std::vector<double>& errors, SmoothedSeries* s) {
  const int n = static_cast<int>(errors.size());
  const Eigen::MatrixXd w = Eigen::Map<const Eigen::VectorXd>(s->weights.data(), n).asDiagonal();
  const Eigen::VectorXd e = Eigen::Map<const Eigen::VectorXd>(errors.data(), n);
  const Eigen::MatrixXd& a = s->basis;
  const Eigen::VectorXd fit = a * (a.transpose() * w * a).ldlt().solve(a.transpose() * w * e);
  for (int i = 0; i < n; ++i) s->residuals[i] = e[i] - fit[i];
}

TEST(ResidualCorrelation, MomentsEqualTheDenseProduct) {
  // Frame gaps, unequal weights and a left-out detection.
  const std::vector<int> frames = {3, 4, 5, 7, 8, 9, 10, 13, 14, 15, 16, 17};
  std::vector<double> weights = {1.0, 2.0, 0.5, 1.0, 0.0, 3.0, 1.0, 1.0, 0.7, 1.2, 1.0, 0.4};
  const SmoothedSeries s = Series(frames, 3, weights);
  const int n = static_cast<int>(frames.size());
  for (double rho : {0.0, 0.35, 0.8}) {
    Eigen::MatrixXd c(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) c(i, j) = std::pow(rho, std::abs(frames[i] - frames[j]));
    const Eigen::MatrixXd w = Eigen::Map<const Eigen::VectorXd>(weights.data(), n).asDiagonal();
    const Eigen::MatrixXd& a = s.basis;
    const Eigen::MatrixXd h = a * (a.transpose() * w * a).inverse() * a.transpose() * w;
    const Eigen::MatrixXd k = Eigen::MatrixXd::Identity(n, n) - h;
    const Eigen::MatrixXd m = k * c * k.transpose();
    const ResidualMoments got = ExpectedResidualMoments(s, rho);
    for (int i = 0; i < n; ++i) EXPECT_NEAR(got.diagonal[i], m(i, i), 1e-12) << rho << " " << i;
    for (int i = 0; i + 1 < n; ++i) EXPECT_NEAR(got.next[i], m(i, i + 1), 1e-12) << rho << " " << i;
  }
}

TEST(ResidualCorrelation, WhiteErrorsGiveTheDegreesOfFreedom) {
  std::vector<int> frames;
  for (int f = 0; f < 20; ++f) frames.push_back(f);
  for (int q : {1, 2, 3}) {
    const SmoothedSeries s = Series(frames, q, std::vector<double>(20, 1.0));
    EXPECT_NEAR(ShrinkageScale(s, 0.0), std::sqrt(20.0 / (20 - q)), 1e-12) << q;
    EXPECT_GT(ShrinkageScale(s, 0.7), ShrinkageScale(s, 0.0) * 1.1) << q;  // correlated errors shrink more
  }
}

// Many tracks of AR(1) errors smoothed by a quadratic: rho is recovered and
// the corrected residuals have the errors' variance; white errors give rho 0.
TEST(ResidualCorrelation, RecoversTheCorrelationAndTheVariance) {
  for (double rho : {0.0, 0.5, std::exp(-1.0 / 3.0)}) {
    std::mt19937 rng(7);
    std::normal_distribution<double> unit(0.0, 1.0);
    std::vector<SmoothedSeries> tracks;
    for (int t = 0; t < 200; ++t) {
      std::vector<int> frames;
      for (int f = 0; f < 25; ++f)
        if (f % 7 != 3) frames.push_back(f);  // a miss now and then
      SmoothedSeries s = Series(frames, 3, std::vector<double>(frames.size(), 1.0));
      std::vector<double> errors;
      double state = unit(rng);
      for (int f = 0, i = 0; f < 25; ++f) {
        if (f > 0) state = rho * state + std::sqrt(1 - rho * rho) * unit(rng);
        if (i < static_cast<int>(frames.size()) && frames[i] == f) errors.push_back(2.0 * state), ++i;
      }
      Smooth(errors, &s);
      tracks.push_back(s);
    }
    const FrameCorrelation estimate = EstimateFrameCorrelation(tracks);
    EXPECT_NEAR(estimate.rho, rho, 0.06);
    EXPECT_GT(estimate.num_pairs, 3000);
    double sum = 0, count = 0, raw = 0;
    for (const SmoothedSeries& s : tracks) {
      const double scale = ShrinkageScale(s, estimate.rho);
      for (double r : s.residuals) sum += r * r * scale * scale, raw += r * r, ++count;
    }
    EXPECT_NEAR(std::sqrt(sum / count), 2.0, 0.1) << rho;
    if (rho > 0.6) EXPECT_LT(std::sqrt(raw / count), 1.5);  // what the smoother leaves uncorrected
  }
}

// The trim keeps the small residuals, whose neighbours are small too: taken
// as they are, the kept pairs read a correlation well below the errors' (at
// a trim of 2 sigmas by about 0.15 here). The estimate compares them with the
// moments of kept normal residuals, so a tight trim reads what a loose one
// reads on the same tracks.
TEST(ResidualCorrelation, TheTrimDoesNotBiasTheCorrelation) {
  const double rho = std::exp(-1.0 / 3.0);
  std::mt19937 rng(11);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::vector<SmoothedSeries> tracks;
  for (int t = 0; t < 600; ++t) {
    std::vector<int> frames;
    for (int f = 0; f < 20; ++f) frames.push_back(f);
    // Unequal weights along the track, as a car that approaches.
    std::vector<double> weights;
    for (int f = 0; f < 20; ++f) weights.push_back(1.0 / (0.3 + 0.05 * f));
    SmoothedSeries s = Series(frames, 3, weights);
    std::vector<double> errors;
    double state = unit(rng);
    for (int f = 0; f < 20; ++f) {
      if (f > 0) state = rho * state + std::sqrt(1 - rho * rho) * unit(rng);
      errors.push_back(state);
    }
    Smooth(errors, &s);
    tracks.push_back(s);
  }
  FrameCorrelationOptions tight, loose;
  tight.trim_sigmas = 2.0, loose.trim_sigmas = 10.0;
  const double at_tight = EstimateFrameCorrelation(tracks, tight).rho;
  const double at_loose = EstimateFrameCorrelation(tracks, loose).rho;
  EXPECT_NEAR(at_loose, rho, 0.06);  // 600 tracks: the estimate scatters by about 0.02
  EXPECT_NEAR(at_tight, at_loose, 0.03);
}

TEST(ResidualCorrelation, TooFewPairsAndBadInput) {
  SmoothedSeries s = Series({0, 1, 2, 3}, 1, {1, 1, 1, 1});
  s.residuals = {0.1, -0.2, 0.3, 0.0};
  const FrameCorrelation none = EstimateFrameCorrelation({s});
  EXPECT_EQ(none.rho, 0.0);
  EXPECT_EQ(none.num_pairs, 3);
  s.frames = {0, 2, 1, 3};
  test::ExpectError([&] { ExpectedResidualMoments(s, 0.5); }, {"frames must increase"});
  s.frames = {0, 1, 2};
  test::ExpectError([&] { ShrinkageScale(s, 0.5); }, {"3 frames but 4 residuals"});
}

}  // namespace
}  // namespace samp
