// The stereo detector model on its own: its error statistics match its
// parameters (medians per distance band, vertical and size spreads, flip and
// miss rates within sampling error, temporal correlation), false positives on
// clutter at the requested rate, determinism by seed; the named profiles and
// the true noise model written for `samp fit --detector-model`.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "libsamp/core/error.h"
#include "libsamp/data/detector_noise.h"
#include "libsamp/synth/detector_model.h"

namespace samp {
namespace {

constexpr double kPi = 3.14159265358979323846;

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double StdDev(const std::vector<double>& v) {
  double mean = 0.0, sq = 0.0;
  for (double x : v) mean += x;
  mean /= double(v.size());
  for (double x : v) sq += (x - mean) * (x - mean);
  return std::sqrt(sq / double(v.size() - 1));
}

ObjectLabel Truth(double distance, double bearing, double yaw) {
  ObjectLabel label;
  label.position = Eigen::Vector3d(distance * std::sin(bearing), 1.65, distance * std::cos(bearing));
  label.position *= distance / label.position.norm();
  label.rotation_y = yaw;
  label.height = 1.5;
  label.width = 1.8;
  label.length = 4.3;
  label.box_2d = Eigen::Vector4d(500, 150, 600, 220);
  return label;
}

struct Draws {
  std::vector<double> near_error, far_error, vertical, size, along_ray, lateral, lag_pairs_a, lag_pairs_b;
  int detections = 0, visible = 0, flips = 0, non_missed = 0;
};

// Tracks of 21 frames at a fixed distance each; near tracks in [5, 20) m, far ones in [40, 45] m.
Draws Simulate(const DetectorModelOptions& options, uint64_t seed, int num_tracks) {
  StereoDetectorModel model(options, seed);
  const PinholeCamera camera;
  Draws draws;
  for (int track = 0; track < num_tracks; ++track) {
    const bool near = track % 2 == 0;
    const double distance = near ? 5.0 + 15.0 * ((track * 37) % 100) / 100.0 : 40.0 + 5.0 * ((track * 53) % 100) / 100.0;
    const double bearing = (((track * 17) % 21) - 10) * 0.03;
    const ObjectLabel truth = Truth(distance, bearing, 0.3);
    double previous = 0.0;
    for (int frame = 0; frame < 21; ++frame) {
      ObjectLabel det;
      DetectionError error;
      ++draws.visible;
      const bool detected = model.Detect(track, frame, truth, 1000, camera, &det, &error);
      if (frame > 0 && near) {
        draws.lag_pairs_a.push_back(previous);
        draws.lag_pairs_b.push_back(error.along_ray);
      }
      previous = error.along_ray;
      if (!detected) continue;
      ++draws.detections;
      const double e = (det.position - truth.position).norm();
      (near ? draws.near_error : draws.far_error).push_back(e);
      draws.vertical.push_back(det.position.y() - truth.position.y());
      draws.size.push_back(det.length - truth.length);
      double dyaw = std::remainder(det.rotation_y - truth.rotation_y, 2.0 * kPi);
      if (std::abs(dyaw) > 0.5 * kPi) ++draws.flips;
    }
  }
  return draws;
}

TEST(DetectorModel, DefaultsMatchTheStereoDetectorTargets) {
  const DetectorModelOptions options;  // the defaults of `samp synth`
  const Draws d = Simulate(options, 7, 2000);
  // A stereo detector: median position error about 0.35 m below 20 m and about 0.6 m beyond 40 m.
  EXPECT_NEAR(Median(d.near_error), 0.35, 0.03);
  EXPECT_NEAR(Median(d.far_error), 0.60, 0.04);
  // Vertical std 0.2-0.3 m, size std ~0.3 m.
  EXPECT_NEAR(StdDev(d.vertical), options.vertical_sigma, 0.02);
  EXPECT_GE(StdDev(d.vertical), 0.2);
  EXPECT_LE(StdDev(d.vertical), 0.3);
  EXPECT_NEAR(StdDev(d.size), options.size_sigma, 0.025);
  // Flips 5-8 %, misses ~5 %: within ~4 sigma of the binomial error, inflated
  // by the run length (correlated draws count as fewer independent ones).
  const double flip_rate = double(d.flips) / d.detections;
  const double flip_sigma = std::sqrt(options.flip_probability * (1 - options.flip_probability) *
                                      (2 * options.flip_mean_run_frames) / d.detections);
  EXPECT_NEAR(flip_rate, options.flip_probability, 4 * flip_sigma);
  EXPECT_GE(flip_rate, 0.05);
  EXPECT_LE(flip_rate, 0.08);
  const double miss_rate = 1.0 - double(d.detections) / d.visible;
  const double miss_sigma = std::sqrt(options.miss_probability * (1 - options.miss_probability) *
                                      (2 * options.miss_mean_run_frames) / d.visible);
  EXPECT_NEAR(miss_rate, options.miss_probability, 4 * miss_sigma);
}

TEST(DetectorModel, ErrorsAreTemporallyCorrelated) {
  DetectorModelOptions options;
  options.correlation_frames = 3.0;
  Draws d = Simulate(options, 3, 600);
  auto correlation = [](const std::vector<double>& a, const std::vector<double>& b) {
    double ma = 0, mb = 0;
    for (size_t i = 0; i < a.size(); ++i) ma += a[i], mb += b[i];
    ma /= a.size();
    mb /= b.size();
    double sab = 0, saa = 0, sbb = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      sab += (a[i] - ma) * (b[i] - mb);
      saa += (a[i] - ma) * (a[i] - ma);
      sbb += (b[i] - mb) * (b[i] - mb);
    }
    return sab / std::sqrt(saa * sbb);
  };
  EXPECT_NEAR(correlation(d.lag_pairs_a, d.lag_pairs_b), std::exp(-1.0 / 3.0), 0.05);
  options.correlation_frames = 0.0;
  d = Simulate(options, 3, 600);
  EXPECT_NEAR(correlation(d.lag_pairs_a, d.lag_pairs_b), 0.0, 0.05);
}

TEST(DetectorModel, ErrorLargestAlongTheRay) {
  DetectorModelOptions options;
  StereoDetectorModel model(options, 5);
  const PinholeCamera camera;
  std::vector<double> along, lateral;
  for (int track = 0; track < 400; ++track) {
    const ObjectLabel truth = Truth(30.0, 0.2, 0.0);
    ObjectLabel det;
    DetectionError error;
    model.Detect(track, 0, truth, 1000, camera, &det, &error);
    along.push_back(error.along_ray);
    lateral.push_back(error.lateral);
  }
  const double expected_along = options.ray_sigma_a + options.ray_sigma_b * 30.0 + options.ray_sigma_c * 900.0;
  EXPECT_NEAR(StdDev(along), expected_along, 0.1 * expected_along);
  EXPECT_GT(StdDev(along), 2.0 * StdDev(lateral));
}

TEST(DetectorModel, SmallCarsAreNeverDetected) {
  DetectorModelOptions options;
  options.miss_probability = 0.0;
  StereoDetectorModel model(options, 1);
  ObjectLabel det;
  EXPECT_FALSE(model.Detect(0, 0, Truth(20.0, 0.0, 0.0), options.min_pixels - 1, PinholeCamera(), &det));
  EXPECT_TRUE(model.Detect(1, 0, Truth(20.0, 0.0, 0.0), options.min_pixels, PinholeCamera(), &det));
}

TEST(DetectorModel, FalsePositivesAtTheRequestedRate) {
  DetectorModelOptions options;
  options.false_positives_per_frame = 0.5;
  options.false_positive_mean_run_frames = 3.0;
  StereoDetectorModel model(options, 9);
  std::vector<ClutterCandidate> candidates;
  for (int i = 0; i < 20; ++i) {
    ClutterCandidate c;
    c.id = i;
    c.position = Eigen::Vector3d((i % 2 ? 4.0 : -4.0), 1.65, 8.0 + 2.0 * i);
    candidates.push_back(c);
  }
  int total = 0;
  const int frames = 4000;
  for (int frame = 0; frame < frames; ++frame) {
    const std::vector<ObjectLabel> fps = model.FalsePositives(frame, candidates, PinholeCamera());
    total += int(fps.size());
    for (const ObjectLabel& fp : fps) {
      EXPECT_GT(fp.box_2d[2], fp.box_2d[0]);
      EXPECT_LT(fp.score, 1.0);
    }
  }
  EXPECT_NEAR(double(total) / frames, 0.5, 0.08);
  options.false_positives_per_frame = 0.0;
  StereoDetectorModel none(options, 9);
  EXPECT_TRUE(none.FalsePositives(0, candidates, PinholeCamera()).empty());
}

TEST(DetectorModel, DeterministicAndIndependentPerTrack) {
  const DetectorModelOptions options;
  StereoDetectorModel a(options, 11), b(options, 11);
  const ObjectLabel truth = Truth(25.0, 0.1, 1.0);
  ObjectLabel da, db, other;
  b.Detect(99, 0, truth, 1000, PinholeCamera(), &other);  // another track first: must not matter
  for (int frame = 0; frame < 5; ++frame) {
    const bool ha = a.Detect(3, frame, truth, 1000, PinholeCamera(), &da);
    const bool hb = b.Detect(3, frame, truth, 1000, PinholeCamera(), &db);
    ASSERT_EQ(ha, hb);
    if (ha) EXPECT_TRUE(da.position.isApprox(db.position));
  }
  EXPECT_THROW(a.Detect(3, 2, truth, 1000, PinholeCamera(), &da), Error) << "frames must increase";
}

TEST(DetectorModel, RejectsBadOptions) {
  DetectorModelOptions options;
  options.flip_probability = 1.5;
  EXPECT_THROW(options.Check(), Error);
  options = DetectorModelOptions();
  options.miss_mean_run_frames = 0.5;
  EXPECT_THROW(options.Check(), Error);
  options = DetectorModelOptions();
  options.vertical_sigma = -0.1;
  EXPECT_THROW(StereoDetectorModel(options, 1), Error);
}

// Every field of the options, by name (the profiles' changes are checked against it).
std::vector<std::pair<std::string, double>> Fields(const DetectorModelOptions& o) {
  return {{"ray_sigma_a", o.ray_sigma_a},
          {"ray_sigma_b", o.ray_sigma_b},
          {"ray_sigma_c", o.ray_sigma_c},
          {"lateral_sigma_a", o.lateral_sigma_a},
          {"lateral_sigma_b", o.lateral_sigma_b},
          {"vertical_sigma", o.vertical_sigma},
          {"size_sigma", o.size_sigma},
          {"relative_size_sigma", o.relative_size_sigma},
          {"height_bias", o.height_bias},
          {"width_bias", o.width_bias},
          {"length_bias", o.length_bias},
          {"along_ray_bias", o.along_ray_bias},
          {"yaw_sigma_deg_a", o.yaw_sigma_deg_a},
          {"yaw_sigma_deg_b", o.yaw_sigma_deg_b},
          {"flip_probability", o.flip_probability},
          {"flip_mean_run_frames", o.flip_mean_run_frames},
          {"miss_probability", o.miss_probability},
          {"miss_mean_run_frames", o.miss_mean_run_frames},
          {"correlation_frames", o.correlation_frames},
          {"false_positives_per_frame", o.false_positives_per_frame},
          {"false_positive_mean_run_frames", o.false_positive_mean_run_frames},
          {"box_sigma_px", o.box_sigma_px},
          {"min_pixels", double(o.min_pixels)}};
}

// The fields of `profile` that differ from the defaults, with their factor
// (value / default; the value itself when the default is 0).
std::map<std::string, double> Changes(const DetectorModelOptions& profile) {
  const auto base = Fields(DetectorModelOptions()), changed = Fields(profile);
  std::map<std::string, double> out;
  for (size_t i = 0; i < base.size(); ++i) {
    if (changed[i].second == base[i].second) continue;
    out[base[i].first] = base[i].second != 0.0 ? changed[i].second / base[i].second : changed[i].second;
  }
  return out;
}

TEST(DetectorProfiles, SetTheFieldsTheyClaim) {
  EXPECT_EQ(DetectorProfileNames(),
            (std::vector<std::string>{"default", "lidar", "stereo-x2", "size-x3", "kitti-boxes", "flips"}));
  for (const std::string& name : DetectorProfileNames()) {
    EXPECT_EQ(DetectorProfile(name).profile, name);
    EXPECT_NO_THROW(DetectorProfile(name).Check()) << name;
  }
  EXPECT_TRUE(Changes(DetectorProfile("default")).empty());
  EXPECT_TRUE(DetectorModelOptions().profile.empty());
  // Position, size and yaw sigmas scaled (c and the relative size sigma are 0 by default).
  const std::vector<std::string> sigmas = {"ray_sigma_a", "ray_sigma_b", "lateral_sigma_a", "lateral_sigma_b",
                                           "vertical_sigma", "size_sigma", "yaw_sigma_deg_a", "yaw_sigma_deg_b"};
  for (const auto& [name, factor] : {std::pair<std::string, double>{"lidar", 0.25}, {"stereo-x2", 2.0}}) {
    const auto changes = Changes(DetectorProfile(name));
    EXPECT_EQ(changes.size(), sigmas.size()) << name;
    for (const std::string& field : sigmas) {
      ASSERT_TRUE(changes.count(field)) << name << " " << field;
      EXPECT_DOUBLE_EQ(changes.at(field), factor) << name << " " << field;
    }
  }
  const auto size = Changes(DetectorProfile("size-x3"));
  ASSERT_EQ(size.size(), 1u);
  EXPECT_DOUBLE_EQ(size.at("size_sigma"), 3.0);
  const auto kitti = Changes(DetectorProfile("kitti-boxes"));
  EXPECT_EQ(kitti.size(), 2u);
  EXPECT_GE(kitti.at("width_bias"), -0.3);
  EXPECT_LE(kitti.at("width_bias"), -0.2);
  EXPECT_NE(kitti.at("along_ray_bias"), 0.0);
  const DetectorModelOptions flips = DetectorProfile("flips");
  EXPECT_EQ(flips.flip_probability, 0.08);
  EXPECT_EQ(Changes(flips).size(), 2u);  // the share and the run length
  try {
    DetectorProfile("radar");
    ADD_FAILURE() << "an unknown profile must throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'radar'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("kitti-boxes"), std::string::npos) << e.what();
  }
}

// The default profile draws exactly what the default options draw (existing
// sequences stay bit-identical).
TEST(DetectorProfiles, DefaultDrawsAreUnchanged) {
  StereoDetectorModel a(DetectorModelOptions(), 21), b(DetectorProfile("default"), 21);
  for (int track = 0; track < 20; ++track) {
    const ObjectLabel truth = Truth(8.0 + 2.0 * track, 0.05 * (track - 10), 0.4);
    for (int frame = 0; frame < 10; ++frame) {
      ObjectLabel da, db;
      ASSERT_EQ(a.Detect(track, frame, truth, 1000, PinholeCamera(), &da),
                b.Detect(track, frame, truth, 1000, PinholeCamera(), &db));
      EXPECT_EQ(da.position, db.position);
      EXPECT_EQ(da.width, db.width);
      EXPECT_EQ(da.length, db.length);
      EXPECT_EQ(da.rotation_y, db.rotation_y);
    }
  }
}

// KITTI-convention boxes are narrower than the true extent by the profile's
// bias on average, and nearer along the ray; the other profiles' are not.
TEST(DetectorProfiles, KittiBoxesAreNarrowerAndNearer) {
  auto mean_errors = [](const DetectorModelOptions& options, double* width, double* along) {
    StereoDetectorModel model(options, 13);
    double sum_width = 0.0, sum_along = 0.0;
    int n = 0;
    for (int track = 0; track < 1000; ++track) {
      const ObjectLabel truth = Truth(6.0 + 0.035 * track, 0.0006 * (track - 500), 0.2);
      for (int frame = 0; frame < 10; ++frame) {
        ObjectLabel det;
        DetectionError error;
        if (!model.Detect(track, frame, truth, 1000, PinholeCamera(), &det, &error)) continue;
        sum_width += det.width - truth.width;
        sum_along += error.along_ray;
        ++n;
      }
    }
    *width = sum_width / n;
    *along = sum_along / n;
  };
  double kitti_width = 0, kitti_along = 0, default_width = 0, default_along = 0;
  const DetectorModelOptions kitti = DetectorProfile("kitti-boxes");
  mean_errors(kitti, &kitti_width, &kitti_along);
  mean_errors(DetectorProfile("default"), &default_width, &default_along);
  // ~9,500 detections in 1,000 tracks of correlated errors: the standard error of the mean width is ~0.01 m.
  EXPECT_NEAR(kitti_width, kitti.width_bias, 0.04);
  EXPECT_NEAR(default_width, 0.0, 0.04);
  EXPECT_LE(kitti_width - default_width, -0.2);
  EXPECT_GE(kitti_width - default_width, -0.3);
  EXPECT_NEAR(kitti_along, kitti.along_ray_bias, 0.05);
  EXPECT_NEAR(default_along, 0.0, 0.05);
}

// The true noise model of every profile: its fields are the options' (exact
// where the format can express them), and the file round-trips through the
// writer and reader of data/detector_noise.h.
TEST(DetectorProfiles, TrueModelMatchesTheOptionsAndRoundTrips) {
  const std::string folder = (std::filesystem::temp_directory_path() / "samp_detector_profiles").string();
  std::filesystem::create_directories(folder);
  for (const std::string& name : DetectorProfileNames()) {
    const DetectorModelOptions o = DetectorProfile(name);
    const DetectorNoiseModel m = TrueDetectorNoiseModel(o, 5.0, 45.0);
    EXPECT_NE(m.source.find(name), std::string::npos);
    EXPECT_EQ(m.along_sigma_a, o.ray_sigma_a) << name;  // c = 0: exact
    EXPECT_EQ(m.along_sigma_b, o.ray_sigma_b) << name;
    EXPECT_EQ(m.across_sigma_a, o.lateral_sigma_a) << name;
    EXPECT_EQ(m.across_sigma_b, o.lateral_sigma_b) << name;
    EXPECT_EQ(m.vertical_sigma_a, o.vertical_sigma) << name;
    EXPECT_EQ(m.vertical_sigma_b, 0.0) << name;
    EXPECT_EQ(m.along_bias, o.along_ray_bias) << name;
    // Sizes: the clipped errors' moments at the typical box (ClippedNormal, tested below).
    const double bias[3] = {o.height_bias, o.width_bias, o.length_bias};
    const double typical_size[3] = {1.5, 1.8, 4.3};
    for (int i = 0; i < 3; ++i) {
      const ClippedNormalMoments e = ClippedNormal(bias[i], o.size_sigma, -0.5 * typical_size[i]);
      EXPECT_EQ(m.size_sigma[i], e.sigma) << name;
      EXPECT_EQ(m.size_bias[i], e.mean) << name;
      EXPECT_LE(m.size_sigma[i], o.size_sigma) << name;
    }
    // The yaw sigma a + b d as its RMS over 5-45 m: between its ends, above its mean.
    const double yaw_near = o.yaw_sigma_deg_a + 5.0 * o.yaw_sigma_deg_b;
    const double yaw_far = o.yaw_sigma_deg_a + 45.0 * o.yaw_sigma_deg_b;
    EXPECT_GE(m.yaw_sigma_deg, 0.5 * (yaw_near + yaw_far)) << name;
    EXPECT_LE(m.yaw_sigma_deg, yaw_far) << name;
    EXPECT_EQ(m.flip_rate, o.flip_probability) << name;
    EXPECT_EQ(m.miss_rate, o.miss_probability) << name;
    EXPECT_EQ(m.false_positives_per_frame, o.false_positives_per_frame) << name;
    EXPECT_TRUE(m.biases_estimated);
    const std::string path = folder + "/" + name + ".json";
    WriteDetectorNoiseModel(path, m);
    const DetectorNoiseModel back = ReadDetectorNoiseModel(path);
    EXPECT_EQ(back.ToJson(), m.ToJson()) << name;
    EXPECT_EQ(back.size_bias[1], m.size_bias[1]) << name;
  }
  std::filesystem::remove_all(folder);
}

// ClippedNormal against cases with known answers: no clip, a clip at the
// mean (a half normal folded onto it), sigma 0, bad arguments.
TEST(DetectorProfiles, ClippedNormalMoments) {
  ClippedNormalMoments e = ClippedNormal(0.2, 0.3, -10.0);
  EXPECT_NEAR(e.mean, 0.2, 1e-12);
  EXPECT_NEAR(e.sigma, 0.3, 1e-12);
  // max(0, z): mean 1 / sqrt(2 pi), variance 1/2 - 1 / (2 pi).
  e = ClippedNormal(1.0, 2.0, 1.0);
  EXPECT_NEAR(e.mean, 1.0 + 2.0 / std::sqrt(2.0 * kPi), 1e-12);
  EXPECT_NEAR(e.sigma, 2.0 * std::sqrt(0.5 - 1.0 / (2.0 * kPi)), 1e-12);
  e = ClippedNormal(-1.0, 0.0, -0.5);
  EXPECT_EQ(e.mean, -0.5);
  EXPECT_EQ(e.sigma, 0.0);
  EXPECT_THROW(ClippedNormal(0.0, -1.0, -1.0), Error);
  EXPECT_THROW(ClippedNormal(std::nan(""), 1.0, -1.0), Error);
}

// The size-x3 detector's boxes at the typical size: the clip at half the true
// size binds (the width's at -1 sigma), and the true model's sigmas and
// biases are what the detector draws; the nominal 0.9 m is not.
TEST(DetectorProfiles, TrueModelSizesAreTheClippedDraws) {
  const DetectorModelOptions o = DetectorProfile("size-x3");
  const DetectorNoiseModel m = TrueDetectorNoiseModel(o, 5.0, 45.0);
  StereoDetectorModel model(o, 29);
  double sum[3] = {0, 0, 0}, sum_sq[3] = {0, 0, 0};
  int n = 0;
  for (int track = 0; track < 2000; ++track) {
    const ObjectLabel truth = Truth(6.0 + 0.018 * track, 0.0003 * (track - 1000), 0.2);
    for (int frame = 0; frame < 10; ++frame) {
      ObjectLabel det;
      if (!model.Detect(track, frame, truth, 1000, PinholeCamera(), &det)) continue;
      const double e[3] = {det.height - truth.height, det.width - truth.width, det.length - truth.length};
      for (int i = 0; i < 3; ++i) sum[i] += e[i], sum_sq[i] += e[i] * e[i];
      ++n;
    }
  }
  ASSERT_GT(n, 15000);
  // 2,000 tracks of AR(1) errors (rho 0.72 over 10 frames, ~2.4 independent
  // draws each): standard errors ~0.015 m for the means, ~0.011 m for the sigmas.
  for (int i = 0; i < 3; ++i) {
    const double mean = sum[i] / n, sigma = std::sqrt(sum_sq[i] / n - mean * mean);
    EXPECT_NEAR(mean, m.size_bias[i], 0.05) << i;
    EXPECT_NEAR(sigma, m.size_sigma[i], 0.04) << i;
  }
  EXPECT_LT(m.size_sigma[1], 0.8);  // the width: 0.78 m
  EXPECT_GT(m.size_bias[1], 0.06);  // +0.075 m
  EXPECT_GT(m.size_sigma[2], 0.85);  // the length's clip at -2.4 sigma hardly binds
}

// Where the format cannot express the options: the along-ray c d^2 becomes the
// least-squares line over the distance range (zero mean error), through
// a = 0.01 m when the free line's a would be lower (the clean preset's
// detector); a relative size sigma is taken at a typical box; each
// approximation is noted. Bad distances and options are errors.
TEST(DetectorProfiles, TrueModelApproximatesWhatTheFormatCannotExpress) {
  DetectorModelOptions o;
  o.ray_sigma_a = 0.3, o.ray_sigma_b = 0.0, o.ray_sigma_c = 0.0005;
  o.size_sigma = 0.0, o.relative_size_sigma = 0.05;
  DetectorNoiseModel m = TrueDetectorNoiseModel(o, 5.0, 45.0);
  double mean_error = 0.0;
  for (int i = 0; i < 400; ++i) {
    const double d = 5.05 + 0.1 * i;  // midpoints of 0.1 m steps
    mean_error += (m.along_sigma_a + m.along_sigma_b * d - (0.3 + 0.0005 * d * d)) / 400.0;
  }
  EXPECT_NEAR(mean_error, 0.0, 1e-4);
  EXPECT_NEAR(m.along_sigma_b, 0.0005 * 2.0 * 25.0, 1e-12);  // the slope of d^2 at the range's centre
  EXPECT_NEAR(m.size_sigma[2], 0.05 * 4.3, 1e-12);
  EXPECT_NEAR(m.size_sigma[1], 0.05 * 1.8, 1e-12);
  auto count_notes = [](const DetectorNoiseModel& model, const std::string& word) {
    int n = 0;
    for (const std::string& note : model.notes) n += note.find(word) != std::string::npos;
    return n;
  };
  EXPECT_EQ(count_notes(m, "least-squares"), 1);
  EXPECT_EQ(count_notes(m, "relative"), 1);
  // The clean preset's detector, 0.1 + 0.001 d^2: the free line would start below 0.
  o.ray_sigma_a = 0.1, o.ray_sigma_c = 0.001;
  m = TrueDetectorNoiseModel(o, 5.0, 45.0);
  EXPECT_EQ(m.along_sigma_a, 0.01);
  EXPECT_GT(m.along_sigma_b, 0.02);
  EXPECT_LT(m.along_sigma_b, 0.06);
  EXPECT_EQ(count_notes(m, "through a = 0.01"), 1);
  EXPECT_THROW(TrueDetectorNoiseModel(o, 10.0, 5.0), Error);
  o.width_bias = std::nan("");
  EXPECT_THROW(TrueDetectorNoiseModel(o, 5.0, 45.0), Error);
}

}  // namespace
}  // namespace samp
