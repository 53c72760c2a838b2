// The stereo detector model on its own: its error statistics match its
// parameters (medians per distance band, vertical and size spreads, flip and
// miss rates within sampling error, temporal correlation), false positives on
// clutter at the requested rate, determinism by seed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "libsamp/core/error.h"
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

}  // namespace
}  // namespace samp
