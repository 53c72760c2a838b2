// How a smoother's residuals shrink when the errors it smooths are correlated
// in time (docs/detector_calibration.md, "Correlated errors").
//
// A track's detections carry errors e with covariance sigma^2 C(rho),
// C_ij = rho^|f_i - f_j| for frames f (an AR(1) process between consecutive
// frames). A linear smoother fitted to them (a polynomial in time, a mean)
// leaves residuals r = (I - H) e with
//
//   H = A (A^T W A)^-1 A^T W,   E[r r^T] = sigma^2 M,   M = (I - H) C (I - H)^T,
//
// A the smoother's basis (n x q), W its weights (0 = a detection it left out).
// For white errors (rho = 0) tr M = n - q, the familiar n - q degrees of
// freedom; for correlated errors the smoother follows part of a slowly
// drifting error and tr M is smaller. ShrinkageScale undoes this:
// r * sqrt(n / sum_i M_ii) has the variance of e. rho is not known: it is
// found by matching the residuals' pooled lag-1 product sum over their
// squares with its expectation under M (EstimateFrameCorrelation).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace samp {

// One cue of one track: the residuals of a linear smoother and what it was.
struct SmoothedSeries {
  std::vector<int> frames;        // increasing frame numbers, one per detection
  Eigen::MatrixXd basis;          // A: n x q, the smoother's basis functions at each detection
  std::vector<double> weights;    // W's diagonal; 0 = left out of the fit
  std::vector<double> residuals;  // r_i, on a common scale across the series of one cue
  std::vector<bool> used;         // enters the statistics (the smoother's inliers)
};

// The diagonal of M and its entries between consecutive detections
// (next[i] = M(i, i + 1), i < n - 1) for the correlation `rho` between frames.
struct ResidualMoments {
  std::vector<double> diagonal, next;
};
ResidualMoments ExpectedResidualMoments(const SmoothedSeries& series, double rho);

// sqrt(sum over used 1 / sum over used M_ii): scales the residuals of
// `series` to the variance of the errors (1 when no detection is used).
double ShrinkageScale(const SmoothedSeries& series, double rho);

struct FrameCorrelationOptions {
  // Residuals beyond trim_sigmas robust sigmas of the pooled residuals do not
  // enter (and the expected moments are those of the kept ones).
  double trim_sigmas = 3.0;
  // Searched in [0, max_rho] on a grid of 5 x step, then of `step` around the best point.
  double max_rho = 0.95, step = 0.01;
  // Fewer lag-1 pairs than this: rho = 0 (white, the smoother's n - q).
  int min_pairs = 30;
};

struct FrameCorrelation {
  double rho = 0.0;       // correlation of the errors between consecutive frames
  int num_pairs = 0;      // lag-1 pairs of used residuals behind it
  bool measured = false;  // at least min_pairs pairs (else rho = 0)
};

// Var[z | |z| <= k] of a standard normal z (0 for k <= 0): what a trim at k
// standard deviations leaves of a unit variance.
double TruncatedNormalVariance(double k);

// Divides the residuals of `series` (one cue) by their robust sigma, 1.4826
// times the median |r_i| of the used ones, so that cues in different units
// can enter one EstimateFrameCorrelation together. No change when every used
// residual is 0.
void NormaliseSeries(std::vector<SmoothedSeries>* series);

// The rho in [0, max_rho] whose expected ratio of sum r_i r_{i+1} (pairs of
// consecutive frames) to sum r_i^2 over the used residuals within the trim
// is nearest to the observed one. The expectations are those of normal
// residuals with covariance M given that the trim kept them, so the trim,
// which keeps the small residuals and their small neighbours, does not bias
// rho low.
FrameCorrelation EstimateFrameCorrelation(const std::vector<SmoothedSeries>& series,
                                          const FrameCorrelationOptions& options = FrameCorrelationOptions());

}  // namespace samp
