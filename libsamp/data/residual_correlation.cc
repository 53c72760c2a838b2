#include "libsamp/data/residual_correlation.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "libsamp/core/error.h"

namespace samp {
namespace {

void CheckSeries(const SmoothedSeries& s) {
  const size_t n = s.frames.size();
  SAMP_CHECK(s.residuals.size() == n && s.weights.size() == n && s.used.size() == n &&
             static_cast<size_t>(s.basis.rows()) == n)
      << "SmoothedSeries: " << n << " frames but " << s.residuals.size() << " residuals, " << s.weights.size()
      << " weights, " << s.used.size() << " flags and " << s.basis.rows() << " basis rows";
  for (size_t i = 1; i < n; ++i)
    SAMP_CHECK(s.frames[i] > s.frames[i - 1]) << "SmoothedSeries: frames must increase (" << s.frames[i - 1]
                                               << " then " << s.frames[i] << ")";
}

// Whether residual i enters the statistics: used and within the trim.
std::vector<bool> Kept(const SmoothedSeries& s, double limit) {
  std::vector<bool> kept(s.frames.size());
  for (size_t i = 0; i < kept.size(); ++i) kept[i] = s.used[i] && std::abs(s.residuals[i]) <= limit;
  return kept;
}

double MedianOf(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// 1.4826 x the median |r_i| over the used residuals of every series (checked).
double RobustSigma(const std::vector<SmoothedSeries>& series) {
  std::vector<double> magnitudes;
  for (const SmoothedSeries& s : series) {
    CheckSeries(s);
    for (size_t i = 0; i < s.residuals.size(); ++i)
      if (s.used[i]) magnitudes.push_back(std::abs(s.residuals[i]));
  }
  return 1.4826 * MedianOf(magnitudes);
}

constexpr double kInvSqrt2Pi = 0.3989422804014327;
double Density(double z) { return kInvSqrt2Pi * std::exp(-0.5 * z * z); }
double Cumulative(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

// Moments of a standard bivariate normal (u, v) with correlation r kept within
// |u| <= h and |v| <= k: P(both kept) and E[u v; both kept]. Given u, v is
// normal with mean r u and variance 1 - r^2, so the inner integral over v is
// closed; the outer one over u (even in u) is a 16-node Gauss-Legendre rule on [0, h].
void KeptPairMoments(double r, double h, double k, double* probability, double* product) {
  static constexpr double kNodes[8] = {0.0950125098376374, 0.2816035507792589, 0.4580167776572274,
                                       0.6178762444026438, 0.7554044083550030, 0.8656312023878318,
                                       0.9445750230732326, 0.9894009349916499};
  static constexpr double kWeights[8] = {0.1894506104550685, 0.1826034150449236, 0.1691565193950025,
                                         0.1495959888165767, 0.1246289712555339, 0.0951585116824928,
                                         0.0622535239386479, 0.0271524594117541};
  const double sd = std::sqrt(std::max(1.0 - r * r, 1e-12));
  double p = 0, m = 0;
  for (int side = -1; side <= 1; side += 2) {
    for (int n = 0; n < 8; ++n) {
      const double u = 0.5 * h * (1.0 + side * kNodes[n]), w = 0.5 * h * kWeights[n] * Density(u);
      const double mean = r * u, lo = (-k - mean) / sd, hi = (k - mean) / sd;
      const double kept = Cumulative(hi) - Cumulative(lo);
      p += w * kept;
      m += w * u * (mean * kept - sd * (Density(hi) - Density(lo)));
    }
  }
  *probability = 2.0 * p, *product = 2.0 * m;
}

}  // namespace

double TruncatedNormalVariance(double k) {
  if (k <= 1e-6) return 0.0;
  return 1.0 - 2.0 * k * Density(k) / std::erf(k / std::sqrt(2.0));
}

// M = C - H C - C H^T + H C H^T with H = A G A^T W, G = (A^T W A)^-1:
// with P = G A^T W C (q x n) and Q = P W A G (q x q),
// M_ij = C_ij - a_i^T P_j - a_j^T P_i + a_i^T Q a_j.
ResidualMoments ExpectedResidualMoments(const SmoothedSeries& s, double rho) {
  CheckSeries(s);
  const int n = static_cast<int>(s.frames.size()), q = static_cast<int>(s.basis.cols());
  ResidualMoments m;
  m.diagonal.assign(n, 1.0);
  m.next.assign(n > 0 ? n - 1 : 0, 0.0);
  if (n == 0) return m;
  // rho^d up to the distance beyond which it is below 1e-12 (a band of C).
  const int span = s.frames.back() - s.frames.front();
  const int reach = rho <= 0 ? 0 : std::min(span, static_cast<int>(std::ceil(std::log(1e-12) / std::log(rho))));
  std::vector<double> power(span + 1, 0.0);
  power[0] = 1.0;
  for (int d = 1; d <= reach; ++d) power[d] = power[d - 1] * rho;
  for (int i = 0; i + 1 < n; ++i) m.next[i] = power[s.frames[i + 1] - s.frames[i]];
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(q, q);
  for (int k = 0; k < n; ++k) normal += s.weights[k] * s.basis.row(k).transpose() * s.basis.row(k);
  if (q == 0 || normal.trace() <= 0) return m;
  const Eigen::MatrixXd g = normal.ldlt().solve(Eigen::MatrixXd::Identity(q, q));
  // W A (n x q) times C, column by column: (A^T W C)_j = sum_k w_k a_k C_kj.
  Eigen::MatrixXd awc = Eigen::MatrixXd::Zero(q, n);
  for (int k = 0, lo = 0, hi = 0; k < n; ++k) {
    while (s.frames[k] - s.frames[lo] > reach) ++lo;
    while (hi + 1 < n && s.frames[hi + 1] - s.frames[k] <= reach) ++hi;
    if (s.weights[k] == 0) continue;
    const Eigen::VectorXd wa = s.weights[k] * s.basis.row(k).transpose();
    for (int j = lo; j <= hi; ++j) awc.col(j) += wa * power[std::abs(s.frames[j] - s.frames[k])];
  }
  const Eigen::MatrixXd p = g * awc;
  Eigen::MatrixXd pwa = Eigen::MatrixXd::Zero(q, q);
  for (int k = 0; k < n; ++k) pwa += s.weights[k] * p.col(k) * s.basis.row(k);
  const Eigen::MatrixXd qm = pwa * g;
  auto entry = [&](int i, int j, double c) {
    return c - s.basis.row(i).dot(p.col(j)) - s.basis.row(j).dot(p.col(i)) +
           s.basis.row(i) * qm * s.basis.row(j).transpose();
  };
  for (int i = 0; i < n; ++i) m.diagonal[i] = entry(i, i, 1.0);
  for (int i = 0; i + 1 < n; ++i) m.next[i] = entry(i, i + 1, m.next[i]);
  return m;
}

double ShrinkageScale(const SmoothedSeries& s, double rho) {
  const ResidualMoments m = ExpectedResidualMoments(s, rho);
  double count = 0, trace = 0;
  for (size_t i = 0; i < m.diagonal.size(); ++i)
    if (s.used[i]) count += 1, trace += m.diagonal[i];
  // A smoother that follows its data almost exactly leaves no information on the scale.
  constexpr double kMinShare = 0.05;
  if (count == 0) return 1.0;
  return std::sqrt(count / std::max(trace, kMinShare * count));
}

void NormaliseSeries(std::vector<SmoothedSeries>* series) {
  const double sigma = RobustSigma(*series);
  if (!(sigma > 0)) return;
  for (SmoothedSeries& s : *series)
    for (double& r : s.residuals) r /= sigma;
}

FrameCorrelation EstimateFrameCorrelation(const std::vector<SmoothedSeries>& series,
                                          const FrameCorrelationOptions& o) {
  SAMP_CHECK(o.trim_sigmas > 0 && o.max_rho >= 0 && o.max_rho < 1 && o.step > 0)
      << "FrameCorrelationOptions: trim_sigmas > 0, max_rho in [0, 1) and step > 0 required";
  const double limit = o.trim_sigmas * RobustSigma(series);
  FrameCorrelation result;
  double observed_next = 0, observed_square = 0;
  std::vector<std::vector<bool>> kept;
  for (const SmoothedSeries& s : series) {
    kept.push_back(Kept(s, limit));
    const std::vector<bool>& k = kept.back();
    for (size_t i = 0; i < k.size(); ++i) {
      if (!k[i]) continue;
      observed_square += s.residuals[i] * s.residuals[i];
      if (i + 1 < k.size() && k[i + 1]) observed_next += s.residuals[i] * s.residuals[i + 1], ++result.num_pairs;
    }
  }
  if (result.num_pairs < o.min_pairs || observed_square <= 0) return result;
  result.measured = true;
  const double observed = observed_next / observed_square;
  // The gap between the expected ratio at rho and the observed one. The
  // trim keeps the small residuals, whose products with their neighbours are
  // smaller than the correlation says; so the expected sums are the
  // moments of normal residuals given that they were kept
  // (TruncatedNormalVariance, KeptPairMoments), at the residuals' scale s that makes the kept squares
  // match (the trim's limit is s k_i sqrt(M_ii) for each residual).
  auto gap = [&](double rho) {
    std::vector<ResidualMoments> moments;
    moments.reserve(series.size());
    for (const SmoothedSeries& s : series) moments.push_back(ExpectedResidualMoments(s, rho));
    // The limit in standard deviations of residual i of series t at scale `scale`.
    auto within = [&](size_t t, size_t i, double scale) {
      return limit / (scale * std::sqrt(std::max(moments[t].diagonal[i], 1e-12)));
    };
    // E[r_i^2 | kept] / scale^2, summed over the kept residuals.
    auto kept_squares = [&](double scale) {
      double sum = 0;
      for (size_t t = 0; t < series.size(); ++t)
        for (size_t i = 0; i < kept[t].size(); ++i) {
          if (!kept[t][i]) continue;
          sum += moments[t].diagonal[i] * TruncatedNormalVariance(within(t, i, scale));
        }
      return sum;
    };
    double expected_square = 0, scale = 1.0;
    for (int round = 0; round < 6; ++round) {
      expected_square = kept_squares(scale);
      scale = std::sqrt(observed_square / std::max(expected_square, 1e-12));
    }
    expected_square = kept_squares(scale);
    double expected_next = 0;
    for (size_t t = 0; t < series.size(); ++t) {
      const std::vector<bool>& k = kept[t];
      const ResidualMoments& m = moments[t];
      for (size_t i = 0; i + 1 < k.size(); ++i) {
        if (!k[i] || !k[i + 1]) continue;
        const double sd = std::sqrt(std::max(m.diagonal[i], 1e-12) * std::max(m.diagonal[i + 1], 1e-12));
        const double r = std::clamp(m.next[i] / sd, -0.999999, 0.999999);
        double p, product;
        KeptPairMoments(r, within(t, i, scale), within(t, i + 1, scale), &p, &product);
        expected_next += sd * product / std::max(p, 1e-12);
      }
    }
    return std::abs(expected_next / std::max(expected_square, 1e-12) - observed);
  };
  // A coarse grid (5 steps), then `step` around its best point.
  auto search = [&](double from, double to, double step) {
    double best = from, best_gap = 1e300;
    for (double rho = from; rho <= to + 1e-12; rho += step) {
      const double g = gap(rho);
      if (g < best_gap) best_gap = g, best = rho;
    }
    return best;
  };
  const double coarse = search(0.0, o.max_rho, 5 * o.step);
  result.rho = search(std::max(0.0, coarse - 4 * o.step), std::min(o.max_rho, coarse + 4 * o.step), o.step);
  return result;
}

}  // namespace samp
