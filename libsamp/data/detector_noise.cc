#include "libsamp/data/detector_noise.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/core/pose.h"
#include "libsamp/data/calibration_option_table.h"
#include "libsamp/data/residual_correlation.h"

namespace samp {
namespace {

// Robust centre and spread of a sample: median and 1.4826 MAD, then a few
// rounds of the mean and standard deviation of the values within trim x sigma
// of the centre, the variance corrected for the trimming of a normal
// distribution (Var[z | |z| < k] = 1 - 2 k phi(k) / (2 Phi(k) - 1)).
//
// A gate. Values matched to ground truth within a distance were only kept
// where |v_i| <= limit_i (`limits`, one per value; empty = no gate): a tail
// reaching past the gate is cut on one side more than on the other when the
// centre is not 0, and a window of +-trim sigma around the centre would keep
// the spared side and pull the centre towards 0. So each value's window is
// kept inside its gate, half-width h_i = min(trim sigma, limit_i - |centre|)
// (a value whose window is empty is left out): inside it the value's
// distribution is symmetric about the true centre, and the centre is
// unbiased. The variance is corrected per value for its own window:
// sigma^2 = sum (v_i - c)^2 / (sum V(h_i / sigma) (n - 1) / n) over the n
// values inside, V(k) the truncated variance above (without a gate: the
// plain formula's sum / ((n - 1) V(trim))).
struct RobustEstimate {
  double center = 0.0, sigma = 0.0;
  int count = 0;
};

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const size_t half = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + half, v.end());
  double m = v[half];
  if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + half));
  return m;
}

RobustEstimate Robust(const std::vector<double>& values, double trim, const std::vector<double>& limits = {}) {
  RobustEstimate r;
  r.count = static_cast<int>(values.size());
  if (values.empty()) return r;
  const bool gated = !limits.empty();
  r.center = Median(values);
  std::vector<double> deviations;
  deviations.reserve(values.size());
  for (double v : values) deviations.push_back(std::abs(v - r.center));
  r.sigma = 1.4826 * Median(deviations);
  const double ungated_variance = TruncatedNormalVariance(trim);
  for (int round = 0; round < (gated ? 20 : 5) && r.sigma > 0; ++round) {
    auto half_width = [&](size_t i) {
      return gated ? std::min(trim * r.sigma, limits[i] - std::abs(r.center)) : trim * r.sigma;
    };
    double sum = 0, expected = 0;
    int n = 0;
    for (size_t i = 0; i < values.size(); ++i) {
      const double h = half_width(i);
      if (h > 0 && std::abs(values[i] - r.center) <= h) {
        sum += values[i], ++n;
        expected += gated ? TruncatedNormalVariance(h / r.sigma) : ungated_variance;
      }
    }
    if (n < 2 || expected <= 0) break;
    const double center = sum / n;
    double sum2 = 0;
    for (size_t i = 0; i < values.size(); ++i) {
      const double h = half_width(i);
      if (h > 0 && std::abs(values[i] - r.center) <= h) sum2 += (values[i] - center) * (values[i] - center);
    }
    const double change = std::abs(center - r.center);
    r.center = center;
    r.sigma = gated ? std::sqrt(sum2 / (expected * (n - 1) / n)) : std::sqrt(sum2 / (n - 1) / ungated_variance);
    if (gated && change < 1e-9) break;
  }
  return r;
}

// One detection's residuals against its reference (smoothed track or truth).
struct Residual {
  double distance = 0.0;                     // horizontal, m
  double along = 0.0, across = 0.0, vertical = 0.0;  // m, camera frame of its frame
  double size[3] = {0, 0, 0};                // h, w, l
  double yaw = 0.0;                          // modulo pi, rad
  bool has_position = false, has_size = false, has_yaw = false;
  int car = 0;  // its track (self-calibration) or true car: a distance bin counts the cars it samples
  // The largest |along| and |across| a match gate let through (ground truth
  // matched within a horizontal distance g: sqrt(g^2 - across^2) and
  // sqrt(g^2 - along^2)); infinite without a gate.
  double along_limit = std::numeric_limits<double>::infinity();
  double across_limit = std::numeric_limits<double>::infinity();
};

// The unit horizontal ray through `position` (camera frame) and the horizontal direction across it.
void RayAxes(const Eigen::Vector3d& position, Eigen::Vector3d* ray, Eigen::Vector3d* across) {
  *ray = Eigen::Vector3d(position.x(), 0.0, position.z());
  const double distance = ray->norm();
  *ray = distance > 1e-9 ? Eigen::Vector3d(*ray / distance) : Eigen::Vector3d::UnitZ();
  *across = Eigen::Vector3d(ray->z(), 0.0, -ray->x());
}

// Decomposes an error vector (camera frame) at `position` along the horizontal ray, across it, vertically.
void Decompose(const Eigen::Vector3d& position, const Eigen::Vector3d& error, Residual* r) {
  Eigen::Vector3d ray, across;
  RayAxes(position, &ray, &across);
  r->distance = Eigen::Vector2d(position.x(), position.z()).norm();
  r->along = error.dot(ray);
  r->across = error.dot(across);
  r->vertical = error.y();
  r->has_position = true;
}

// Angle difference modulo pi, in [-pi/2, pi/2).
double AxisDifference(double a, double b) {
  double d = std::fmod(a - b, kPi);
  if (d < -kPi / 2) d += kPi;
  if (d >= kPi / 2) d -= kPi;
  return d;
}

// Heading of a box in the world's horizontal plane (x, z), from its camera's rotation.
double WorldHeading(const ObjectLabel& label, const Eigen::Matrix3d& world_from_camera) {
  const Eigen::Vector3d front =
      world_from_camera * Eigen::Vector3d(std::cos(label.rotation_y), 0.0, -std::sin(label.rotation_y));
  return std::atan2(front.z(), front.x());
}

// Fits sigma(d) = a + b d (a > 0, b >= 0) to the bins' sigmas, weighted by their counts.
bool FitLinear(const std::vector<std::pair<double, double>>& distance_sigma, const std::vector<int>& counts,
               double* a, double* b) {
  if (distance_sigma.empty()) return false;
  double sw = 0, sd = 0, ss = 0, sdd = 0, sds = 0;
  for (size_t i = 0; i < distance_sigma.size(); ++i) {
    const double w = counts[i], d = distance_sigma[i].first, s = distance_sigma[i].second;
    sw += w, sd += w * d, ss += w * s, sdd += w * d * d, sds += w * d * s;
  }
  const double det = sw * sdd - sd * sd;
  if (distance_sigma.size() >= 2 && det > 1e-9 * sw * sdd) {
    *b = (sw * sds - sd * ss) / det;
    *a = (ss - *b * sd) / sw;
  } else {
    *b = 0.0;
    *a = ss / sw;
  }
  constexpr double kMinA = 0.01;
  if (*b < 0) {
    *b = 0.0;
    *a = ss / sw;
  }
  if (*a < kMinA) {  // the slope through the floor
    *a = kMinA;
    *b = sdd > 0 ? std::max(0.0, (sds - kMinA * sd) / sdd) : 0.0;
  }
  return true;
}

// The position sigmas (per distance bin, then a + b d over the bins) and,
// when `with_biases`, the biases. The along-ray bias is the bins' centres
// combined with the weights count / sigma(d)^2 of the fitted line at each
// bin's mean distance (the inverse variances of the centres: far detections
// err more, and pooling them with equal weights costs precision), over the
// bins that enter the fit. Each bin's statistics keep their windows inside
// the residuals' gates (Robust).
void SummarisePosition(const std::vector<Residual>& residuals, const DetectorNoiseOptions& o, bool with_biases,
                       DetectorNoiseModel* model) {
  const size_t num_bins = o.bin_edges.size();
  std::vector<std::vector<double>> along(num_bins), across(num_bins), vertical(num_bins), distance(num_bins);
  std::vector<std::vector<double>> along_limit(num_bins), across_limit(num_bins);
  std::vector<std::set<int>> cars(num_bins);
  bool gated = false;
  for (const Residual& r : residuals) {
    if (!r.has_position) continue;
    ++model->num_position_samples;
    size_t bin = 0;
    while (bin + 1 < num_bins && r.distance >= o.bin_edges[bin + 1]) ++bin;
    along[bin].push_back(r.along), across[bin].push_back(r.across), vertical[bin].push_back(r.vertical);
    along_limit[bin].push_back(r.along_limit), across_limit[bin].push_back(r.across_limit);
    distance[bin].push_back(r.distance);
    cars[bin].insert(r.car);
    gated = gated || std::isfinite(r.along_limit) || std::isfinite(r.across_limit);
  }
  std::vector<std::pair<double, double>> fit_along, fit_across, fit_vertical;
  std::vector<int> fit_counts;
  std::vector<double> fit_along_centers;
  for (size_t b = 0; b < num_bins; ++b) {
    if (along[b].empty()) continue;
    DistanceBin bin;
    bin.min_distance = o.bin_edges[b];
    bin.max_distance = b + 1 < num_bins ? o.bin_edges[b + 1] : 1e3;
    bin.count = static_cast<int>(along[b].size());
    bin.tracks = static_cast<int>(cars[b].size());
    const RobustEstimate ea = Robust(along[b], o.trim_sigmas, gated ? along_limit[b] : std::vector<double>()),
                         ec = Robust(across[b], o.trim_sigmas, gated ? across_limit[b] : std::vector<double>()),
                         ev = Robust(vertical[b], o.trim_sigmas);
    bin.along_sigma = ea.sigma, bin.across_sigma = ec.sigma, bin.vertical_sigma = ev.sigma;
    if (with_biases) bin.along_bias = ea.center, bin.across_bias = ec.center, bin.vertical_bias = ev.center;
    double mean_distance = 0;
    for (double d : distance[b]) mean_distance += d;
    mean_distance /= distance[b].size();
    bin.mean_distance = mean_distance;
    model->bins.push_back(bin);
    if (bin.count < o.min_bin_count) continue;
    if (bin.tracks < o.min_bin_tracks) {
      std::ostringstream note;
      note << "position: the distance bin [" << bin.min_distance << ", " << bin.max_distance << ") m holds "
           << bin.count << " detections of " << bin.tracks << (bin.tracks == 1 ? " car" : " cars") << " (need "
           << o.min_bin_tracks << "): not in the sigma(d) fit";
      model->notes.push_back(note.str());
      continue;
    }
    fit_along.push_back({mean_distance, bin.along_sigma});
    fit_across.push_back({mean_distance, bin.across_sigma});
    fit_vertical.push_back({mean_distance, bin.vertical_sigma});
    fit_counts.push_back(bin.count);
    fit_along_centers.push_back(ea.center);
  }
  if (model->num_position_samples < o.min_samples || fit_counts.empty()) {
    std::ostringstream note;
    note << "position: " << model->num_position_samples << " detections (need " << o.min_samples
         << ", and a distance bin of " << o.min_bin_count << "): the default position sigmas kept";
    model->notes.push_back(note.str());
  } else {
    FitLinear(fit_along, fit_counts, &model->along_sigma_a, &model->along_sigma_b);
    FitLinear(fit_across, fit_counts, &model->across_sigma_a, &model->across_sigma_b);
    FitLinear(fit_vertical, fit_counts, &model->vertical_sigma_a, &model->vertical_sigma_b);
    if (with_biases) {
      double weighted = 0, weights = 0;
      for (size_t i = 0; i < fit_counts.size(); ++i) {
        const double sigma = model->along_sigma_a + model->along_sigma_b * fit_along[i].first;
        const double w = fit_counts[i] / (sigma * sigma);
        weighted += w * fit_along_centers[i], weights += w;
      }
      model->along_bias = weighted / weights;
    }
  }
}

// The box size sigmas (and biases) per dimension.
void SummariseSize(const std::vector<Residual>& residuals, const DetectorNoiseOptions& o, bool with_biases,
                   DetectorNoiseModel* model) {
  std::vector<double> size[3];
  for (const Residual& r : residuals)
    if (r.has_size)
      for (int i = 0; i < 3; ++i) size[i].push_back(r.size[i]);
  model->num_size_samples = static_cast<int>(size[0].size());
  if (model->num_size_samples < o.min_samples) {
    model->notes.push_back("size: " + std::to_string(model->num_size_samples) + " detections (need " +
                           std::to_string(o.min_samples) + "): the default size sigma kept");
  } else {
    for (int i = 0; i < 3; ++i) {
      const RobustEstimate e = Robust(size[i], o.trim_sigmas);
      model->size_sigma[i] = std::max(e.sigma, 1e-3);
      if (with_biases) model->size_bias[i] = e.center;
    }
  }
}

// The yaw sigma, modulo 180 degrees.
void SummariseYaw(const std::vector<Residual>& residuals, const DetectorNoiseOptions& o, DetectorNoiseModel* model) {
  std::vector<double> yaw;
  for (const Residual& r : residuals)
    if (r.has_yaw) yaw.push_back(r.yaw);
  model->num_yaw_samples = static_cast<int>(yaw.size());
  if (model->num_yaw_samples < o.min_samples) {
    model->notes.push_back("yaw: " + std::to_string(model->num_yaw_samples) + " detections (need " +
                           std::to_string(o.min_samples) + "): the default yaw sigma kept");
  } else {
    model->yaw_sigma_deg = std::max(Robust(yaw, o.trim_sigmas).sigma * 180.0 / kPi, 0.01);
  }
}

// Turns residuals into the model's sigmas (and biases when `with_biases`).
void Summarise(const std::vector<Residual>& residuals, const DetectorNoiseOptions& o, bool with_biases,
               const TrackerOptions& defaults, DetectorNoiseModel* model) {
  model->along_sigma_a = defaults.along_sigma_a, model->along_sigma_b = defaults.along_sigma_b;
  model->across_sigma_a = defaults.across_sigma_a, model->across_sigma_b = defaults.across_sigma_b;
  model->vertical_sigma_a = defaults.vertical_sigma_a, model->vertical_sigma_b = defaults.vertical_sigma_b;
  for (double& s : model->size_sigma) s = defaults.size_sigma;
  model->yaw_sigma_deg = defaults.yaw_sigma_deg;
  model->biases_estimated = with_biases;
  SummarisePosition(residuals, o, with_biases, model);
  SummariseSize(residuals, o, with_biases, model);
  SummariseYaw(residuals, o, model);
}

// Least-squares polynomial (degree q - 1) in time of the bottom centre in the
// world, each detection weighted by its information matrix times a robust
// weight; iteratively reweighted (Huber, then Tukey-like rejection).
std::vector<Eigen::Vector3d> SmoothTrack(const std::vector<Eigen::Vector3d>& points,
                                         const std::vector<Eigen::Matrix3d>& information,
                                         const std::vector<double>& times, int q, std::vector<double>* weights) {
  const size_t n = points.size();
  double t_mid = 0;
  for (double t : times) t_mid += t;
  t_mid /= n;
  std::vector<double> robust(n, 1.0);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * q);
  auto row = [&](size_t i) {
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3, 3 * q);
    double power = 1.0;
    for (int k = 0; k < q; ++k, power *= times[i] - t_mid) a.block<3, 3>(0, 3 * k) = power * Eigen::Matrix3d::Identity();
    return a;
  };
  std::vector<Eigen::Vector3d> fitted(n);
  for (int round = 0; round < 8; ++round) {
    Eigen::MatrixXd lhs = 1e-9 * Eigen::MatrixXd::Identity(3 * q, 3 * q);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(3 * q);
    for (size_t i = 0; i < n; ++i) {
      if (robust[i] <= 0) continue;
      const Eigen::MatrixXd a = row(i);
      lhs += robust[i] * a.transpose() * information[i] * a;
      rhs += robust[i] * a.transpose() * information[i] * points[i];
    }
    x = lhs.ldlt().solve(rhs);
    if (round == 7) *weights = robust;  // the weights of this last solve
    for (size_t i = 0; i < n; ++i) {
      fitted[i] = row(i) * x;
      const Eigen::Vector3d r = points[i] - fitted[i];
      const double m = std::sqrt(std::max(0.0, r.dot(information[i] * r)));
      if (round < 4) {
        const double k = 2.0;  // Huber
        robust[i] = m <= k ? 1.0 : k / m;
      } else {
        robust[i] = m <= 4.03 ? 1.0 : 0.0;  // sqrt of chi2(3) at 99.9 %
      }
    }
  }
  return fitted;
}

// The axis (modulo 180 degrees) of a track's box headings: the mean of the
// doubled angles, then the median difference. Returns its direction: of the
// motion when the smoothed track moves faster than 2 m/s, else of most boxes.
double TrackDirection(const std::vector<double>& headings, const std::vector<Eigen::Vector3d>& fitted,
                      const std::vector<double>& times, double* track_axis) {
  double c = 0, s = 0;
  for (double h : headings) c += std::cos(2 * h), s += std::sin(2 * h);
  double axis = 0.5 * std::atan2(s, c);
  std::vector<double> axis_differences;
  for (double h : headings) axis_differences.push_back(AxisDifference(h, axis));
  axis += Median(axis_differences);
  // Its direction: of the motion when the car moves, else of most boxes.
  const Eigen::Vector3d motion = fitted.back() - fitted.front();
  const double duration = times.back() - times.front();
  double direction = axis;
  const Eigen::Vector2d horizontal(motion.x(), motion.z());
  if (duration > 0 && horizontal.norm() / duration > 2.0) {
    const double motion_heading = std::atan2(horizontal.y(), horizontal.x());
    direction = std::cos(motion_heading - axis) >= 0 ? axis : axis + kPi;
  } else {
    int forward = 0;
    for (double h : headings) forward += std::cos(h - axis) >= 0 ? 1 : -1;
    direction = forward >= 0 ? axis : axis + kPi;
  }
  *track_axis = axis;
  return direction;
}

// Flips, directed detections and the frames spanned and missed by the confident tracks.
struct TrackCounts {
  long long flips = 0, directed = 0, spanned = 0, missed = 0;
};

// The cues whose errors may be correlated in time, in DetectorNoiseModel::correlation's order.
enum Cue { kAlong, kAcross, kVertical, kHeight, kWidth, kLength, kYaw, kNumCues };

// One confident track's residuals, not yet corrected for the smoother's
// shrinkage, and per cue the smoother that left them (residual_correlation.h).
struct TrackResiduals {
  std::vector<Residual> residuals;
  SmoothedSeries series[kNumCues];
};

// The standard deviations along the horizontal ray, across it and vertically of `covariance` at `position`.
Eigen::Vector3d DecomposedSigmas(const Eigen::Vector3d& position, const Eigen::Matrix3d& covariance) {
  Eigen::Vector3d ray, across;
  RayAxes(position, &ray, &across);
  return Eigen::Vector3d(std::sqrt(ray.dot(covariance * ray)), std::sqrt(across.dot(covariance * across)),
                         std::sqrt(covariance(1, 1)));
}

// The residuals of one confident track's detections against its smoothed
// trajectory, its median box and its axis; counts its flips and interior misses.
TrackResiduals TrackResidualsOf(const LinkedTrack& track, const std::map<int, const FrameDetections*>& frame_of,
                                const DetectorNoiseOptions& o, const TrackerOptions& defaults, TrackCounts* counts) {
  const int n = static_cast<int>(track.detections.size());
  std::vector<Eigen::Vector3d> points(n);
  std::vector<Eigen::Matrix3d> information(n), rotation(n);
  std::vector<double> times(n), headings(n);
  for (int i = 0; i < n; ++i) {
    const ObjectLabel& d = track.detections[i];
    const auto it = frame_of.find(d.frame);
    SAMP_CHECK(it != frame_of.end()) << "EstimateDetectorNoise: a track's detection is in frame " << d.frame
                                     << ", which the sequence does not list";
    const Eigen::Isometry3d& pose = it->second->world_from_camera;
    rotation[i] = pose.linear();
    points[i] = pose * d.position;
    information[i] = (rotation[i] * DetectionCovariance(d.position, defaults) * rotation[i].transpose()).inverse();
    times[i] = d.frame / defaults.frame_rate_hz;
    headings[i] = WorldHeading(d, rotation[i]);
  }
  // Interior misses: frames of the sequence within the track's span without its detection.
  const auto first = frame_of.find(track.detections.front().frame);
  const auto last = frame_of.find(track.detections.back().frame);
  const long long span = std::distance(first, last) + 1;
  counts->spanned += span;
  counts->missed += span - n;

  const int q = (o.smoother_degree == 2 && n >= 9) ? 3 : 2;
  std::vector<double> robust;
  const std::vector<Eigen::Vector3d> fitted = SmoothTrack(points, information, times, q, &robust);
  double median_size[3];
  for (int k = 0; k < 3; ++k) {
    std::vector<double> v;
    for (const ObjectLabel& d : track.detections) v.push_back(k == 0 ? d.height : k == 1 ? d.width : d.length);
    median_size[k] = Median(v);
  }
  double axis = 0.0;
  const double direction = TrackDirection(headings, fitted, times, &axis);
  TrackResiduals out;
  const double t_mid = std::accumulate(times.begin(), times.end(), 0.0) / n;
  for (int c = 0; c < kNumCues; ++c) {
    SmoothedSeries& s = out.series[c];
    const int columns = c <= kVertical ? q : 1;  // the trajectory's polynomial; the median box and axis: a mean
    s.basis.resize(n, columns);
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < columns; ++k) s.basis(i, k) = std::pow(times[i] - t_mid, k);
    s.weights.assign(n, 1.0);
    s.used.assign(n, true);
    s.residuals.resize(n);
    for (const ObjectLabel& d : track.detections) s.frames.push_back(d.frame);
  }
  for (int i = 0; i < n; ++i) {
    const ObjectLabel& d = track.detections[i];
    Residual r;
    Decompose(d.position, rotation[i].transpose() * (points[i] - fitted[i]), &r);
    r.size[0] = d.height - median_size[0];
    r.size[1] = d.width - median_size[1];
    r.size[2] = d.length - median_size[2];
    r.has_size = true;
    r.yaw = AxisDifference(headings[i], axis);
    r.has_yaw = true;
    out.residuals.push_back(r);
    counts->flips += std::cos(headings[i] - direction) < 0;
    ++counts->directed;
    // Position cues on the scale of the current model (one scale across tracks), weighted as the smoother weighs them.
    const Eigen::Vector3d sigma = DecomposedSigmas(d.position, DetectionCovariance(d.position, defaults));
    const double position[3] = {r.along, r.across, r.vertical};
    for (int c = kAlong; c <= kVertical; ++c) {
      SmoothedSeries& s = out.series[c];
      s.residuals[i] = position[c] / sigma[c];
      s.weights[i] = robust[i] / (sigma[c] * sigma[c]);
      s.used[i] = robust[i] > 0;
    }
    for (int k = 0; k < 3; ++k) out.series[kHeight + k].residuals[i] = r.size[k];
    out.series[kYaw].residuals[i] = r.yaw;
  }
  return out;
}

// Estimates each cue's correlation between frames from the residuals of every
// track (one value for all cues when a cue has too few pairs for its own; or
// 0 = white), and scales each track's residuals to the variance of the
// errors: a smoother with q parameters per coordinate leaves n - q degrees of
// freedom of white errors, fewer of correlated ones.
// Returns a note when the correlation could not be measured.
std::string CorrectShrinkage(const DetectorNoiseOptions& o, std::vector<TrackResiduals>* tracks,
                             DetectorNoiseModel* model) {
  std::string note;
  double rho[kNumCues] = {0, 0, 0, 0, 0, 0, 0};
  if (o.correct_correlation) {
    FrameCorrelationOptions co;
    co.trim_sigmas = o.trim_sigmas;
    std::vector<SmoothedSeries> cues[kNumCues];
    FrameCorrelation per_cue[kNumCues];
    int fewest_pairs = -1;
    for (int c = 0; c < kNumCues; ++c) {
      for (const TrackResiduals& t : *tracks) cues[c].push_back(t.series[c]);
      per_cue[c] = EstimateFrameCorrelation(cues[c], co);
      fewest_pairs = fewest_pairs < 0 ? per_cue[c].num_pairs : std::min(fewest_pairs, per_cue[c].num_pairs);
    }
    const bool shared = fewest_pairs < o.correlation_pairs_per_cue;
    int pairs = fewest_pairs;
    if (shared) {
      std::vector<SmoothedSeries> all;
      for (std::vector<SmoothedSeries>& cue : cues) {
        NormaliseSeries(&cue);
        all.insert(all.end(), cue.begin(), cue.end());
      }
      const FrameCorrelation f = EstimateFrameCorrelation(all, co);
      std::fill(rho, rho + kNumCues, f.rho);
      pairs = f.num_pairs;
    } else {
      for (int c = 0; c < kNumCues; ++c) rho[c] = per_cue[c].rho;
    }
    if (pairs >= co.min_pairs) {
      std::copy(rho, rho + kNumCues, model->correlation);
      model->correlation_pairs = pairs;
      model->correlation_shared = shared;
      model->correlation_estimated = true;
    } else {
      std::fill(rho, rho + kNumCues, 0.0);
      note = "correlation: " + std::to_string(std::max(pairs, 0)) + " pairs of consecutive detections (need " +
             std::to_string(co.min_pairs) + "): white errors assumed";
    }
  }
  for (TrackResiduals& t : *tracks) {
    for (int c = 0; c < kNumCues; ++c) {
      const double scale = ShrinkageScale(t.series[c], rho[c]);
      for (Residual& r : t.residuals) {
        double* value = c == kAlong      ? &r.along
                        : c == kAcross   ? &r.across
                        : c == kVertical ? &r.vertical
                        : c == kYaw      ? &r.yaw
                                         : &r.size[c - kHeight];
        *value *= scale;
      }
    }
  }
  return note;
}

}  // namespace

void DetectorNoiseOptions::Check() const {
  DetectorNoiseOptionTable().Check(*this);
}

DetectorNoiseModel EstimateDetectorNoise(const std::vector<LinkedSequence>& sequences,
                                         const DetectorNoiseOptions& o, const TrackerOptions& defaults) {
  o.Check();
  defaults.Check();
  DetectorNoiseModel model;
  model.source = "self-calibration";
  std::vector<TrackResiduals> tracks;
  TrackCounts counts;
  long long in_confident = 0, all_detections = 0;
  for (const LinkedSequence& seq : sequences) {
    std::map<int, const FrameDetections*> frame_of;
    for (const FrameDetections& f : seq.frames) frame_of[f.frame] = &f;
    model.num_frames += static_cast<int>(seq.frames.size());
    all_detections += seq.num_detections;
    for (const LinkedTrack& track : seq.tracks) {
      const int n = static_cast<int>(track.detections.size());
      if (n < o.min_track_detections) continue;
      ++model.num_tracks;
      in_confident += n;
      tracks.push_back(TrackResidualsOf(track, frame_of, o, defaults, &counts));
      for (Residual& r : tracks.back().residuals) r.car = model.num_tracks;
    }
  }
  const std::string correlation_note = CorrectShrinkage(o, &tracks, &model);
  std::vector<Residual> residuals;
  for (const TrackResiduals& t : tracks) residuals.insert(residuals.end(), t.residuals.begin(), t.residuals.end());
  Summarise(residuals, o, /*with_biases=*/false, defaults, &model);
  if (!correlation_note.empty()) model.notes.push_back(correlation_note);
  model.flip_rate = counts.directed > 0 ? double(counts.flips) / counts.directed : 0.0;
  model.miss_rate = counts.spanned > 0 ? double(counts.missed) / counts.spanned : 0.0;
  model.false_positives_per_frame =
      model.num_frames > 0 ? double(std::max(0LL, all_detections - in_confident)) / model.num_frames : 0.0;
  model.source = model.num_position_samples >= o.min_samples ? "self-calibration" : "defaults";
  return model;
}

void BoxConventionOptions::Check() const { BoxConventionOptionTable().Check(*this); }

int EstimateBoxConvention(const std::vector<BoxConventionSample>& samples, const BoxConventionOptions& o,
                          DetectorNoiseModel* model) {
  o.Check();
  for (double& b : model->size_bias) b = 0.0;
  for (double& e : model->size_bias_error) e = 0.0;
  model->along_bias = 0.0, model->along_bias_error = 0.0;
  model->box_convention_estimated = false;
  // Per quantity (h, w, l, along) and car: the differences of the detections
  // that pass the gates and observe that quantity.
  std::map<int, std::vector<double>> of_car[4];
  std::map<int, int> cars;
  int used = 0;
  for (const BoxConventionSample& s : samples) {
    if (!(s.distance <= o.max_distance) || s.num_points < o.min_points) continue;
    bool finite = std::isfinite(s.along) && std::isfinite(s.view_angle_deg);
    for (int i = 0; i < 3; ++i) finite = finite && std::isfinite(s.detected[i] - s.fitted[i]) && s.fitted[i] > 0;
    if (!finite) continue;
    of_car[0][s.car].push_back(s.detected[0] - s.fitted[0]);
    if (s.view_angle_deg <= o.max_end_view_deg) of_car[1][s.car].push_back(s.detected[1] - s.fitted[1]);
    if (s.view_angle_deg >= o.min_side_view_deg) of_car[2][s.car].push_back(s.detected[2] - s.fitted[2]);
    of_car[3][s.car].push_back(s.along);
    ++cars[s.car];
    ++used;
  }
  model->box_convention_tracks = static_cast<int>(cars.size());
  model->box_convention_detections = used;
  if (model->box_convention_tracks < o.min_cars || used < o.min_detections) {
    std::ostringstream note;
    note << "box convention: " << model->box_convention_tracks << " car(s) and " << used
         << " detection(s) within " << o.max_distance << " m with >= " << o.min_points << " points (need "
         << o.min_cars << " and " << o.min_detections << "): the box biases kept at 0";
    model->notes.push_back(note.str());
    return used;
  }
  // Median per car, then the median over the cars and its standard error.
  double* bias[4] = {&model->size_bias[0], &model->size_bias[1], &model->size_bias[2], &model->along_bias};
  double* error[4] = {&model->size_bias_error[0], &model->size_bias_error[1], &model->size_bias_error[2],
                      &model->along_bias_error};
  const char* names[4] = {"height", "width", "length", "along-ray"};
  for (int k = 0; k < 4; ++k) {
    if (static_cast<int>(of_car[k].size()) < o.min_cars) {
      std::ostringstream note;
      note << "box convention: the " << names[k] << " is observed on " << of_car[k].size() << " car(s) (need "
           << o.min_cars << "; the width from behind or in front, the length from the side): kept at 0";
      model->notes.push_back(note.str());
      continue;
    }
    std::vector<double> per_car;
    for (const auto& [car, values] : of_car[k]) per_car.push_back(Median(values));
    const double center = Median(per_car);
    std::vector<double> deviations;
    for (double v : per_car) deviations.push_back(std::abs(v - center));
    // At least 1 cm: a handful of cars that agree exactly do not make any offset significant.
    const double se = std::max(0.01, 1.253 * 1.4826 * Median(deviations) / std::sqrt(double(per_car.size())));
    *error[k] = se;
    if (std::abs(center) < o.min_significance * se) {
      std::ostringstream note;
      note << "box convention: the " << names[k] << " bias " << center << " m is within " << o.min_significance
           << " standard errors (" << se << " m) of 0: kept at 0";
      model->notes.push_back(note.str());
      *bias[k] = 0.0;
    } else {
      *bias[k] = center;
    }
  }
  model->box_convention_estimated = true;
  return used;
}

DetectorNoiseModel EstimateDetectorNoiseFromTruth(const std::vector<MatchedDetection>& matches, int num_missed,
                                                  int num_false_positives, int num_frames,
                                                  const DetectorNoiseOptions& o, const TrackerOptions& defaults,
                                                  double match_distance) {
  o.Check();
  defaults.Check();
  SAMP_CHECK(match_distance > 0) << "EstimateDetectorNoiseFromTruth: match_distance must be > 0 (infinity: no gate)";
  SAMP_CHECK(num_missed >= 0 && num_false_positives >= 0 && num_frames >= 0)
      << "EstimateDetectorNoiseFromTruth: negative counts";
  DetectorNoiseModel model;
  std::vector<Residual> residuals;
  std::map<int, int> cars;
  int flips = 0;
  for (const MatchedDetection& m : matches) {
    Residual r;
    Decompose(m.truth.position, m.detection.position - m.truth.position, &r);
    if (std::isfinite(match_distance)) {
      r.along_limit = std::sqrt(std::max(0.0, match_distance * match_distance - r.across * r.across));
      r.across_limit = std::sqrt(std::max(0.0, match_distance * match_distance - r.along * r.along));
    }
    r.size[0] = m.detection.height - m.truth.height;
    r.size[1] = m.detection.width - m.truth.width;
    r.size[2] = m.detection.length - m.truth.length;
    r.has_size = true;
    r.yaw = AxisDifference(m.detection.rotation_y, m.truth.rotation_y);
    r.has_yaw = true;
    r.car = m.truth_id;
    flips += std::abs(WrapAngle(m.detection.rotation_y - m.truth.rotation_y)) > kPi / 2;
    residuals.push_back(r);
    ++cars[m.truth_id];
  }
  Summarise(residuals, o, /*with_biases=*/true, defaults, &model);
  model.source = model.num_position_samples >= o.min_samples ? "ground truth" : "defaults";
  model.num_tracks = static_cast<int>(cars.size());
  model.num_frames = num_frames;
  model.flip_rate = matches.empty() ? 0.0 : double(flips) / matches.size();
  const double truths = double(matches.size()) + num_missed;
  model.miss_rate = truths > 0 ? num_missed / truths : 0.0;
  model.false_positives_per_frame = num_frames > 0 ? double(num_false_positives) / num_frames : 0.0;
  return model;
}

}  // namespace samp
