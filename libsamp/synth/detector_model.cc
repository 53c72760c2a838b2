#include "libsamp/synth/detector_model.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/core/pose.h"
#include "libsamp/synth/procedural.h"
#include "libsamp/synth/synth_option_table.h"

namespace samp {
namespace {

// Two-state Markov chain with stationary probability p of the "on" state and
// mean run length L frames of that state: P(on -> off) = 1 / L,
// P(off -> on) = p / (1 - p) / L. L = 0: independent draws.
struct MarkovRates {
  double enter = 0.0, exit = 1.0;
};

MarkovRates Rates(double p, double mean_run) {
  MarkovRates r;
  if (mean_run <= 0.0 || p <= 0.0 || p >= 1.0) {
    r.enter = p;
    r.exit = 1.0 - p;
  } else {
    r.exit = 1.0 / mean_run;
    r.enter = p / (1.0 - p) / mean_run;
  }
  return r;
}

}  // namespace

void DetectorModelOptions::Check() const { DetectorModelOptionTable().Check(*this); }

struct StereoDetectorModel::TrackState {
  explicit TrackState(uint64_t seed) : engine(seed) {}
  std::mt19937_64 engine;
  int last_frame = 0;
  bool started = false;
  // Standardised AR(1) states: along ray, lateral, vertical, h, w, l, yaw.
  double ar[7] = {0, 0, 0, 0, 0, 0, 0};
  bool flipped = false, missed = false;
};

StereoDetectorModel::StereoDetectorModel(const DetectorModelOptions& options, uint64_t seed)
    : options_(options), seed_(seed), clutter_engine_(procedural::Mix(seed, 0xC177u)) {
  options_.Check();
}

StereoDetectorModel::~StereoDetectorModel() = default;

StereoDetectorModel::TrackState& StereoDetectorModel::State(int track_id) {
  auto it = tracks_.find(track_id);
  if (it == tracks_.end()) {
    it = tracks_.emplace(track_id, std::make_unique<TrackState>(procedural::Mix(seed_, uint64_t(track_id) + 17)))
             .first;
  }
  return *it->second;
}

bool StereoDetectorModel::Detect(int track_id, int frame, const ObjectLabel& truth, int visible_pixels,
                                 const PinholeCamera& camera, ObjectLabel* detection,
                                 DetectionError* error) {
  TrackState& s = State(track_id);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const MarkovRates flip = Rates(options_.flip_probability, options_.flip_mean_run_frames);
  const MarkovRates miss = Rates(options_.miss_probability, options_.miss_mean_run_frames);
  if (!s.started) {
    for (double& a : s.ar) a = normal(s.engine);
    s.flipped = uniform(s.engine) < options_.flip_probability;
    s.missed = uniform(s.engine) < options_.miss_probability;
    s.started = true;
  } else {
    SAMP_CHECK(frame > s.last_frame) << "detector model: track " << track_id << ": frame " << frame
                                     << " after frame " << s.last_frame << " (frames must increase)";
    const int gap = frame - s.last_frame;
    const double rho = options_.correlation_frames > 0 ? std::exp(-double(gap) / options_.correlation_frames)
                                                       : 0.0;
    const double innovation = std::sqrt(std::max(0.0, 1.0 - rho * rho));
    for (double& a : s.ar) a = rho * a + innovation * normal(s.engine);
    for (int step = 0; step < gap; ++step) {
      const double u_flip = uniform(s.engine), u_miss = uniform(s.engine);
      s.flipped = s.flipped ? !(u_flip < flip.exit) : (u_flip < flip.enter);
      s.missed = s.missed ? !(u_miss < miss.exit) : (u_miss < miss.enter);
    }
  }
  s.last_frame = frame;
  double box_noise[4];
  for (double& b : box_noise) b = normal(s.engine);
  const double score_noise = normal(s.engine);

  const Eigen::Vector3d p = truth.position;
  const double d = p.norm();
  const Eigen::Vector3d ray = Eigen::Vector3d(p.x(), 0.0, p.z()).normalized();
  const Eigen::Vector3d lateral(ray.z(), 0.0, -ray.x());
  DetectionError e;
  e.along_ray = options_.along_ray_bias + (options_.ray_sigma_a + options_.ray_sigma_b * d + options_.ray_sigma_c * d * d) * s.ar[0];
  e.lateral = (options_.lateral_sigma_a + options_.lateral_sigma_b * d) * s.ar[1];
  e.vertical = options_.vertical_sigma * s.ar[2];
  e.yaw_rad = (options_.yaw_sigma_deg_a + options_.yaw_sigma_deg_b * d) * kPi / 180.0 * s.ar[6];
  e.flipped = s.flipped;
  if (error) *error = e;

  ObjectLabel det = truth;
  det.frame = -1;
  det.track_id = -1;
  det.position = p + e.along_ray * ray + e.lateral * lateral + Eigen::Vector3d(0.0, e.vertical, 0.0);
  det.position.z() = std::max(det.position.z(), 0.5);  // never behind the camera (documented)
  det.rotation_y = WrapAngle(truth.rotation_y + e.yaw_rad + (e.flipped ? kPi : 0.0));
  auto noisy_size = [&](double size, double bias, double standard) {
    return std::max(0.5 * size,
                    size + bias + (options_.size_sigma + options_.relative_size_sigma * size) * standard);
  };
  det.height = noisy_size(truth.height, options_.height_bias, s.ar[3]);
  det.width = noisy_size(truth.width, options_.width_bias, s.ar[4]);
  det.length = noisy_size(truth.length, options_.length_bias, s.ar[5]);
  Eigen::Vector4d b = truth.box_2d;
  for (int i = 0; i < 4; ++i) b[i] += options_.box_sigma_px * box_noise[i];
  b[0] = std::clamp(b[0], 0.0, camera.width - 2.0);
  b[1] = std::clamp(b[1], 0.0, camera.height - 2.0);
  b[2] = std::clamp(b[2], b[0] + 1.0, camera.width - 1.0);
  b[3] = std::clamp(b[3], b[1] + 1.0, camera.height - 1.0);
  det.box_2d = b;
  det.alpha = WrapAngle(det.rotation_y - std::atan2(det.position.x(), det.position.z()));
  det.score = std::clamp(0.97 - 0.008 * d + 0.03 * score_noise, 0.05, 1.0);
  if (s.missed || visible_pixels < options_.min_pixels) return false;
  *detection = det;
  return true;
}

const std::vector<std::string>& DetectorProfileNames() {
  static const std::vector<std::string> names = {"default", "lidar", "stereo-x2", "size-x3", "kitti-boxes", "flips"};
  return names;
}

DetectorModelOptions DetectorProfile(const std::string& name) {
  DetectorModelOptions o;
  // Position, size and yaw sigmas times `factor` (rates, correlation and the 2D box stay).
  auto scale_sigmas = [&o](double factor) {
    for (double* v : {&o.ray_sigma_a, &o.ray_sigma_b, &o.ray_sigma_c, &o.lateral_sigma_a, &o.lateral_sigma_b,
                      &o.vertical_sigma, &o.size_sigma, &o.relative_size_sigma, &o.yaw_sigma_deg_a,
                      &o.yaw_sigma_deg_b})
      *v *= factor;
  };
  if (name == "default") {
  } else if (name == "lidar") {
    scale_sigmas(0.25);
  } else if (name == "stereo-x2") {
    scale_sigmas(2.0);
  } else if (name == "size-x3") {
    o.size_sigma *= 3.0;
    o.relative_size_sigma *= 3.0;
  } else if (name == "kitti-boxes") {
    o.width_bias = -0.25;      // KITTI's boxes exclude the mirrors (0.2-0.3 m of a CAD car's width)
    o.along_ray_bias = -0.2;   // boxes placed on the visible surface: nearer than the true centre
  } else if (name == "flips") {
    o.flip_probability = 0.08;
    o.flip_mean_run_frames = 1.0;  // every flip lasts one frame: 5x the default's flip events
  } else {
    std::ostringstream known;
    for (const std::string& n : DetectorProfileNames()) known << (known.tellp() > 0 ? ", " : "") << n;
    SAMP_THROW() << "detector model: unknown profile '" << name << "' (known: " << known.str() << ")";
  }
  o.profile = name;
  return o;
}

ClippedNormalMoments ClippedNormal(double mean, double sigma, double floor) {
  SAMP_CHECK(std::isfinite(mean) && std::isfinite(sigma) && std::isfinite(floor) && sigma >= 0.0)
      << "detector model: clipped normal needs a finite mean, floor and sigma >= 0 (are " << mean << ", " << floor
      << ", " << sigma << ")";
  if (sigma == 0.0) return {std::max(mean, floor), 0.0};
  // e = mean + sigma max(a, z), a = (floor - mean) / sigma, z standard normal:
  // E max(a, z) = a Phi(a) + phi(a), E max(a, z)^2 = a^2 Phi(a) + 1 - Phi(a) + a phi(a).
  const double a = (floor - mean) / sigma;
  const double cdf = 0.5 * std::erfc(-a / std::sqrt(2.0));
  const double pdf = std::exp(-0.5 * a * a) / std::sqrt(2.0 * kPi);
  const double first = a * cdf + pdf;
  const double second = a * a * cdf + (1.0 - cdf) + a * pdf;
  return {mean + sigma * first, sigma * std::sqrt(std::max(0.0, second - first * first))};
}

DetectorNoiseModel TrueDetectorNoiseModel(const DetectorModelOptions& o, double min_distance, double max_distance) {
  o.Check();
  SAMP_CHECK(std::isfinite(min_distance) && std::isfinite(max_distance) && min_distance >= 0.0 &&
             max_distance > min_distance)
      << "detector model: true noise model needs 0 <= min_distance < max_distance (are " << min_distance << ", "
      << max_distance << ")";
  DetectorNoiseModel m;
  m.source = o.profile.empty() ? "synthetic detector" : "synthetic detector, profile " + o.profile;
  std::ostringstream range;
  range << min_distance << "-" << max_distance << " m";
  m.notes.push_back("the generating noise of the synthetic detector for cars at " + range.str() +
                    " (no samples; sample counts are 0)");
  // The format's sigmas must be > 0: a zero sigma becomes 1 mm, with a note.
  auto positive = [&m](double value, const char* name) {
    if (value >= 1e-3) return value;
    m.notes.push_back(std::string(name) + ": " + std::to_string(value) + " m raised to 0.001 (the format needs > 0)");
    return 1e-3;
  };
  // Least-squares line of d^2 over [d0, d1]: d^2 ~ 2 m d - m^2 + h^2 / 3 (m the centre, h the half width).
  const double centre = 0.5 * (min_distance + max_distance), half = 0.5 * (max_distance - min_distance);
  m.along_sigma_a = o.ray_sigma_a + o.ray_sigma_c * (half * half / 3.0 - centre * centre);
  m.along_sigma_b = o.ray_sigma_b + o.ray_sigma_c * 2.0 * centre;
  if (o.ray_sigma_c != 0.0) {
    std::ostringstream note;
    note << "along the ray: a + b d + c d^2 (c " << o.ray_sigma_c << ") as its least-squares line over " << range.str();
    constexpr double kMinA = 0.01;  // as the estimators' a >= 0.01 m
    if (m.along_sigma_a < kMinA) {  // the least-squares slope through a = 0.01 m
      const double d0 = min_distance, d1 = max_distance;
      const double moment = (o.ray_sigma_a - kMinA) * (d1 * d1 - d0 * d0) / 2.0 +
                            o.ray_sigma_b * (d1 * d1 * d1 - d0 * d0 * d0) / 3.0 +
                            o.ray_sigma_c * (d1 * d1 * d1 * d1 - d0 * d0 * d0 * d0) / 4.0;
      m.along_sigma_a = kMinA;
      m.along_sigma_b = std::max(0.0, moment / ((d1 * d1 * d1 - d0 * d0 * d0) / 3.0));
      note << " through a = " << kMinA << " m";
    }
    m.notes.push_back(note.str());
  }
  m.along_sigma_a = positive(m.along_sigma_a, "along_sigma_a");
  m.across_sigma_a = positive(o.lateral_sigma_a, "across_sigma_a");
  m.across_sigma_b = o.lateral_sigma_b;
  m.vertical_sigma_a = positive(o.vertical_sigma, "vertical_sigma_a");
  m.vertical_sigma_b = 0.0;
  m.along_bias = o.along_ray_bias;
  const double typical_size[3] = {1.5, 1.8, 4.3};
  const double bias[3] = {o.height_bias, o.width_bias, o.length_bias};
  bool clipped = false;
  for (int i = 0; i < 3; ++i) {
    const double nominal = o.size_sigma + o.relative_size_sigma * typical_size[i];
    const ClippedNormalMoments e = ClippedNormal(bias[i], nominal, -0.5 * typical_size[i]);  // as Detect clips
    clipped = clipped || std::abs(e.sigma - nominal) > 1e-3;
    m.size_sigma[i] = positive(e.sigma, "size.sigma");
    m.size_bias[i] = e.mean;
  }
  if (o.relative_size_sigma != 0.0)
    m.notes.push_back("size: the relative sigma taken at a box of h 1.5, w 1.8, l 4.3 m");
  if (clipped)
    m.notes.push_back("size: a detected dimension is clipped at half the true one; the sigmas and biases are "
                      "those of the clipped errors at a box of h 1.5, w 1.8, l 4.3 m");
  // Root mean square of a + b d over [d0, d1].
  const double a = o.yaw_sigma_deg_a, b = o.yaw_sigma_deg_b;
  m.yaw_sigma_deg = std::max(0.01, std::sqrt(a * a + 2 * a * b * centre + b * b * (centre * centre + half * half / 3.0)));
  if (b != 0.0) m.notes.push_back("yaw: a + b d as its root mean square over " + range.str());
  if (o.correlation_frames > 0.0) {
    std::ostringstream note;
    note << "the errors are correlated in time (AR(1), tau " << o.correlation_frames
         << " frames); the format assumes white noise";
    m.notes.push_back(note.str());
  }
  m.flip_rate = o.flip_probability;
  m.miss_rate = o.miss_probability;
  m.false_positives_per_frame = o.false_positives_per_frame;
  m.biases_estimated = true;
  return m;
}

std::vector<ObjectLabel> StereoDetectorModel::FalsePositives(int frame,
                                                             const std::vector<ClutterCandidate>& candidates,
                                                             const PinholeCamera& camera) {
  (void)frame;
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::map<int, const ClutterCandidate*> visible;
  std::map<int, Eigen::Vector4d> boxes;
  for (const ClutterCandidate& c : candidates) {
    ObjectLabel probe;
    probe.position = c.position;
    probe.rotation_y = c.rotation_y;
    probe.height = c.height;
    probe.width = c.width;
    probe.length = c.length;
    Eigen::Vector4d box;
    if (c.position.z() > 3.0 && ProjectBox(probe, camera, &box)) {
      visible[c.id] = &c;
      boxes[c.id] = box;
    }
  }
  // Survival of the false positives alive so far (they die with their candidate's visibility).
  const double survive = 1.0 - 1.0 / options_.false_positive_mean_run_frames;
  std::vector<FalsePositiveState> next;
  for (const FalsePositiveState& fp : alive_) {
    if (visible.count(fp.candidate_id) && uniform(clutter_engine_) < survive) next.push_back(fp);
  }
  // Births: Poisson with mean rate / lifetime, so that rate false positives are alive on average.
  if (!visible.empty() && options_.false_positives_per_frame > 0) {
    std::poisson_distribution<int> births(options_.false_positives_per_frame /
                                          options_.false_positive_mean_run_frames);
    const int n = births(clutter_engine_);
    for (int k = 0; k < n; ++k) {
      auto it = visible.begin();
      std::advance(it, std::uniform_int_distribution<int>(0, int(visible.size()) - 1)(clutter_engine_));
      bool taken = false;
      for (const FalsePositiveState& fp : next) taken = taken || fp.candidate_id == it->first;
      if (taken) continue;
      FalsePositiveState fp;
      fp.candidate_id = it->first;
      fp.along = 0.4 * normal(clutter_engine_);
      fp.lateral = 0.2 * normal(clutter_engine_);
      fp.yaw = (uniform(clutter_engine_) < 0.5 ? 0.0 : kPi) + 0.1 * normal(clutter_engine_);
      next.push_back(fp);
    }
  }
  alive_ = std::move(next);
  std::vector<ObjectLabel> out;
  for (const FalsePositiveState& fp : alive_) {
    const ClutterCandidate& c = *visible.at(fp.candidate_id);
    ObjectLabel det;
    det.type = "Car";
    det.height = c.height;
    det.width = c.width;
    det.length = c.length;
    const Eigen::Vector3d ray = Eigen::Vector3d(c.position.x(), 0.0, c.position.z()).normalized();
    const Eigen::Vector3d lateral(ray.z(), 0.0, -ray.x());
    det.position = c.position + (fp.along + 0.1 * normal(clutter_engine_)) * ray +
                   (fp.lateral + 0.05 * normal(clutter_engine_)) * lateral;
    det.rotation_y = WrapAngle(c.rotation_y + fp.yaw);
    if (!ProjectBox(det, camera, &det.box_2d)) continue;
    const double d = det.position.norm();
    det.alpha = WrapAngle(det.rotation_y - std::atan2(det.position.x(), det.position.z()));
    det.score = std::clamp(0.75 - 0.008 * d + 0.1 * normal(clutter_engine_), 0.05, 1.0);
    out.push_back(det);
  }
  return out;
}

}  // namespace samp
