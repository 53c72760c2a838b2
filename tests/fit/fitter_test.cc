// End-to-end fits on small synthetic tracks: points sampled from a known
// shape of an in-memory PCA model, moving on a known circular arc (or
// standing), with noise, outliers and flipped detections.
#include "libsamp/fit/fitter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <random>

#include "libsamp/core/error.h"
#include "libsamp/data/sequence.h"
#include "libsamp/fit/costs/disparity.h"
#include "libsamp/fit/track_problem.h"
#include "libsamp/model/shape_model.h"
#include "tests/fit/fit_test_util.h"
#include "tests/testing/expect_error.h"

namespace samp {
namespace {

const ShapeModel& Model() {
  static const ShapeModel model = testing::MakeSyntheticModel(5, 0.1);
  return model;
}

using testing::MakeTrack;
using testing::Synthetic;

// Mean |phi_fit| on the true surface, in the object frame.
double ShapeError(const ShapeLookup& lookup, const Eigen::VectorXd& z_true, const Eigen::VectorXd& z_fit) {
  std::mt19937 rng(99);
  const auto surface = testing::SampleSurface(lookup, z_true, 400, &rng);
  double sum = 0;
  for (const auto& p : surface) sum += std::abs(lookup.Evaluate(z_fit, p));
  return sum / surface.size();
}

TEST(Fitter, OptionsCheck) {
  FitOptions options;
  EXPECT_NO_THROW(options.Check());
  options.linear_solver = "dense_normal_cholesky";
  test::ExpectError([&] { options.Check(); }, {"FitOptions.linear_solver"});
  options = FitOptions();
  options.em_iterations = -1;
  test::ExpectError([&] { options.Check(); }, {"FitOptions.em_iterations"});
  options = FitOptions();
  options.linear_solver = "magic";
  test::ExpectError([&] { options.Check(); }, {"FitOptions.linear_solver"});
}

TEST(Fitter, RecoversShapeAndArcTrajectory) {
  FitOptions options;
  TrackFitter fitter(Model(), options);
  Synthetic s = MakeTrack(fitter.lookup(), 11, 8.0, 0.3, 400, 11, /*flipped_frame=*/5);
  const TrackFit fit = fitter.Fit(s.track);
  EXPECT_TRUE(fit.summary.usable) << fit.summary.BriefReport();
  EXPECT_EQ(fit.summary.solves.size(), 2u);
  EXPECT_LT(fit.summary.final_cost, fit.summary.initial_cost);
  // Shape: with the default prior (lambda = 1, as strong as the whole data
  // term) the MAP shape moves towards the truth; with a weak prior it is
  // recovered within 2.5 cm on average (the mean shape is 7 cm off).
  const double error0 = ShapeError(fitter.lookup(), s.z_true, Eigen::VectorXd::Zero(5));
  const double error = ShapeError(fitter.lookup(), s.z_true, fit.shape_code);
  EXPECT_LT(error, 0.75 * error0) << "mean shape error " << error0;
  // (The paper's term and weighting: the data term is a mean over points, so
  // lambda = 0.02 is a weak prior there.)
  FitOptions weak = options;
  weak.data_term = DataTerm::kPaper;
  weak.data_weighting = DataWeighting::kMean;
  weak.shape_prior_weight = 0.02;
  const TrackFit weak_fit = TrackFitter(Model(), weak).Fit(s.track);
  const double weak_error = ShapeError(fitter.lookup(), s.z_true, weak_fit.shape_code);
  EXPECT_LT(weak_error, 0.025) << "mean shape error " << error0;
  EXPECT_LT((weak_fit.shape_code - s.z_true).cwiseQuotient(fitter.lookup().sigmas()).cwiseAbs().maxCoeff(), 0.5);
  // Poses: 10 cm, 2 degrees; velocities: 0.5 m/s, 0.1 rad/s (middle frames).
  ASSERT_EQ(fit.frames.size(), 11u);
  for (int k = 0; k < 11; ++k) {
    const FrameFit& f = fit.frames[k];
    EXPECT_LT((f.position - s.poses_true[k].head<3>()).norm(), 0.10) << "frame " << k;
    EXPECT_LT(std::abs(WrapAngle(f.yaw - s.poses_true[k][3])), 2.0 * M_PI / 180) << "frame " << k;
    if (k > 0 && k < 10) {
      EXPECT_NEAR(f.speed, 8.0, 0.5) << "frame " << k;
      EXPECT_NEAR(f.yaw_rate, 0.3, 0.1) << "frame " << k;
      EXPECT_EQ(f.motion_model, "arc");
    }
    EXPECT_GT(f.num_points, 280);  // of 400 surface points + 20 clutter
    EXPECT_EQ(int(f.points_in_world.size()), f.num_points);
  }
}

// FitOptions::max_solve_points_per_frame: a solve uses an even subsample of
// each frame's association, weighted as the whole association, so the prior
// and data keep their balance and the fit moves little.
TEST(Fitter, SolvePointCapSubsamplesWithTheWholeAssociationsWeight) {
  FitOptions all;
  all.max_solve_points_per_frame = 0;
  FitOptions capped = all;
  capped.max_solve_points_per_frame = 100;
  const Synthetic s = MakeTrack(TrackFitter(Model(), all).lookup(), 11, 8.0, 0.3, 800, 17);
  const TrackFit fit_all = TrackFitter(Model(), all).Fit(s.track);
  const TrackFit fit_capped = TrackFitter(Model(), capped).Fit(s.track);
  ASSERT_TRUE(fit_all.summary.usable && fit_capped.summary.usable);
  ASSERT_EQ(fit_all.summary.solves.size(), fit_capped.summary.solves.size());
  for (size_t k = 0; k < fit_all.summary.solves.size(); ++k) {
    EXPECT_GT(fit_all.summary.solves[k].num_points, 11 * 500) << "solve " << k;
    EXPECT_EQ(fit_capped.summary.solves[k].num_points, 11 * 100) << "solve " << k;
  }
  // The data weight is that of the whole association: the cost is an
  // estimate of the same energy (weighted by the 100 points, it would be ~8x smaller).
  EXPECT_NEAR(fit_capped.summary.final_cost / fit_all.summary.final_cost, 1.0, 0.3);
  ASSERT_EQ(fit_all.frames.size(), fit_capped.frames.size());
  for (size_t k = 0; k < fit_all.frames.size(); ++k) {
    const FrameFit& a = fit_all.frames[k];
    const FrameFit& c = fit_capped.frames[k];
    // The association (and with it N_eff, the data weight) is that of all points.
    EXPECT_GT(c.num_points, 500) << "frame " << k;
    EXPECT_NEAR(c.effective_points, a.effective_points, 0.1 * a.effective_points) << "frame " << k;
    EXPECT_LT((c.position - a.position).norm(), 0.05) << "frame " << k;
    EXPECT_LT((c.position - s.poses_true[k].head<3>()).norm(), 0.10) << "frame " << k;
  }
  EXPECT_LT(ShapeError(TrackFitter(Model(), all).lookup(), fit_all.shape_code, fit_capped.shape_code), 0.02);
  FitOptions bad = all;
  bad.max_solve_points_per_frame = bad.min_points_per_frame - 1;
  EXPECT_THROW(bad.Check(), Error);
}

TEST(Fitter, StandingCarAndSingleFrameMode) {
  FitOptions options;
  Synthetic s;
  {
    TrackFitter fitter(Model(), options);
    s = MakeTrack(fitter.lookup(), 5, 0.0, 0.0, 300, 12, /*flipped_frame=*/1);
    const TrackFit fit = fitter.Fit(s.track);
    EXPECT_TRUE(fit.summary.usable);
    for (int k = 0; k < 5; ++k) {
      EXPECT_LT((fit.frames[k].position - s.poses_true[k].head<3>()).norm(), 0.10);
      EXPECT_LT(std::abs(WrapAngle(fit.frames[k].yaw - 0.4)), 2.0 * M_PI / 180);
      if (k > 0) {
        EXPECT_EQ(fit.frames[k].motion_model, "standing");
      }
    }
  }
  options.single_frame = true;
  TrackFitter single(Model(), options);
  const TrackFit fit = single.Fit(s.track);
  EXPECT_TRUE(fit.single_frame);
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(fit.frames[k].shape_code.size(), 5);
    EXPECT_EQ(fit.frames[k].motion_model, "none");
    EXPECT_LT((fit.frames[k].position - s.poses_true[k].head<3>()).norm(), 0.2);
  }
  EXPECT_EQ(fit.summary.num_frames_reset, 0);
  // One frame is fine in single-frame mode.
  Track one = s.track;
  one.frames.resize(1);
  EXPECT_EQ(single.Fit(one).frames.size(), 1u);
  // A frame that runs away from its detection is reset to it: a detection
  // 8 m off the car's points fits (if at all) metres from where it started.
  Track far = s.track;
  far.frames[2].detection.position.x() += 8.0;
  options.association_radius = 12.0;  // so that the points still reach the far detection
  // The stereo alone: the detected size would hold the far frame's shape.
  options.detection_size_sigma = 0.0;
  const InitialState init = InitializeTrack(far, options);
  options.max_position_change = 0.05;
  const TrackFit reset = TrackFitter(Model(), options).Fit(far);
  EXPECT_GE(reset.summary.num_frames_reset, 1);
  EXPECT_LT((reset.frames[2].position - init.poses[2].head<3>()).norm(), 1e-9)
      << "reset to the initial pose";
  EXPECT_TRUE(reset.frames[2].shape_code.isZero()) << "and the mean shape";
  options.max_position_change = 0.0;
  EXPECT_THROW(options.Check(), Error);
}

TEST(Fitter, RayDistanceRemovesThePullTowardsTheCameraUnderDepthNoise) {
  // Stereo-like noise: 0.8 m (s.d.) along the viewing ray (from the camera
  // at the world origin), more than the car's half width. With phi as the
  // residual, points pushed behind the visible surface saturate while those
  // in front grow, so the fit moves towards the camera; the ray distance
  // removes most of that pull.
  const ShapeLookup lookup(Model());
  Synthetic s = MakeTrack(lookup, 9, 0.0, 0.0, 400, 21);
  std::mt19937 rng(22);
  std::normal_distribution<double> n(0.0, 1.0);
  for (size_t k = 0; k < s.track.frames.size(); ++k) {
    TrackFrame& f = s.track.frames[k];
    // Stereo sees only the visible surface (and the 5 % clutter stays).
    testing::KeepVisible(lookup, s.z_true, WorldFromObject(s.poses_true[k].head<3>(), s.poses_true[k][3]),
                         Eigen::Vector3d::Zero(), &f.candidate_points_in_world, &f.candidate_sigmas);
  }
  for (TrackFrame& f : s.track.frames) {
    for (size_t i = 0; i < f.candidate_points_in_world.size(); ++i) {
      Eigen::Vector3d& p = f.candidate_points_in_world[i];
      p += 0.8 * n(rng) * p.normalized();
      f.candidate_sigmas[i] = 0.8;
    }
  }
  auto along_ray_error = [&](DataTerm term) {
    FitOptions options;
    options.data_term = term;
    options.data_weighting = DataWeighting::kMean;
    options.em_iterations = 0;
    const TrackFit fit = TrackFitter(Model(), options).Fit(s.track);
    EXPECT_TRUE(fit.summary.usable);
    double sum = 0.0;
    for (size_t k = 0; k < fit.frames.size(); ++k) {
      const Eigen::Vector3d truth = s.poses_true[k].head<3>();
      sum += (fit.frames[k].position - truth).dot(truth.normalized());
    }
    return sum / double(fit.frames.size());
  };
  const double sdf_error = along_ray_error(DataTerm::kPaper), ray_error = along_ray_error(DataTerm::kRayDepth);
  const double disparity_error = along_ray_error(DataTerm::kDisparity);
  // Measured: -0.35 m (phi), -0.19 m (ray depth), within +-0.05 m (disparity).
  EXPECT_LT(sdf_error, -0.15) << "the phi residual is expected to pull towards the camera";
  EXPECT_LT(std::abs(ray_error), std::abs(sdf_error));
  // Each point against the visible surface on its own ray: no pull.
  EXPECT_LT(std::abs(disparity_error), 0.05) << "phi " << sdf_error << ", ray depth " << ray_error << ", disparity " << disparity_error;
}

TEST(Fitter, DisparityFitDropsAndCountsPointsBehindTheCamera) {
  // Candidates behind the camera (at the world origin, looking along +z)
  // and one at depth 0 beside it: the disparity term has no residual for
  // them. The fit drops and counts them in both associations (the
  // detection's and the EM pass's) instead of throwing.
  const ShapeLookup lookup(Model());
  Synthetic s = MakeTrack(lookup, 5, 8.0, 0.0, 200, 31);
  Synthetic clean = s;
  int planted = 0;
  for (TrackFrame& f : s.track.frames) {
    const Eigen::Vector3d ahead = f.candidate_points_in_world[0];
    for (const Eigen::Vector3d& p : {Eigen::Vector3d(-ahead), Eigen::Vector3d(-0.1 * ahead),
                                     Eigen::Vector3d(ahead.x(), ahead.y(), 0.0)}) {
      f.candidate_points_in_world.push_back(p);
      f.candidate_sigmas.push_back(50.0);  // would pass the ray gate
      ++planted;
    }
  }
  FitOptions options;
  options.data_term = DataTerm::kDisparity;
  options.em_iterations = 1;
  const TrackFitter fitter(Model(), options);
  TrackFit fit;
  ASSERT_NO_THROW(fit = fitter.Fit(s.track));
  EXPECT_TRUE(fit.summary.usable) << fit.summary.BriefReport();
  EXPECT_EQ(fit.summary.solves.size(), 2u);
  EXPECT_EQ(fit.summary.num_points_behind_camera, planted);
  EXPECT_NE(fit.summary.BriefReport().find(std::to_string(planted) + " points behind the camera dropped"),
            std::string::npos)
      << fit.summary.BriefReport();
  // Dropped, not used: the same fit as without them.
  const TrackFit reference = fitter.Fit(clean.track);
  EXPECT_EQ(reference.summary.num_points_behind_camera, 0);
  EXPECT_EQ(fit.shape_code, reference.shape_code);
  for (size_t k = 0; k < fit.frames.size(); ++k) EXPECT_EQ(fit.frames[k].position, reference.frames[k].position);
  // The cost itself still refuses such a point (the fit never gives it one).
  DataCostOptions cost_options = DataTermOptions(s.track, s.track.frames[0], options, 1.0);
  EXPECT_THROW(DisparityCost(&lookup, {Eigen::Vector3d(0.0, 0.0, -5.0)}, {0.1}, cost_options), Error);
}

// Height of the shape phi_z (extent of phi < 0 along object y), m.
double Height(const ShapeLookup& lookup, const Eigen::VectorXd& z) {
  const AlignedBox box = lookup.InsideBox(z);
  return box.max.y() - box.min.y();
}

// The component whose +-2 sigma changes the inside box's extent along `axis`
// (0 length, 1 height, 2 width) most.
int ComponentChangingMost(const ShapeLookup& lookup, int axis) {
  const int nr = lookup.num_components();
  int component = 0;
  double best = 0.0;
  for (int r = 0; r < nr; ++r) {
    Eigen::VectorXd plus = Eigen::VectorXd::Zero(nr), minus = plus;
    plus[r] = 2.0 * lookup.sigmas()[r];
    minus[r] = -2.0 * lookup.sigmas()[r];
    const double change = std::abs(lookup.InsideBox(plus).Size()[axis] - lookup.InsideBox(minus).Size()[axis]);
    if (change > best) best = change, component = r;
  }
  return component;
}

// Stereo noise along each point's ray (camera at the world origin): disparity
// noise of sigma_disp px, sigma_d from the measured depth as the observations do.
void AddDisparityNoise(double sigma_disp, std::normal_distribution<double>& n, std::mt19937& rng, TrackFrame* f) {
  const double bf = 0.54 * 721.5;
  for (size_t i = 0; i < f->candidate_points_in_world.size(); ++i) {
    Eigen::Vector3d& p = f->candidate_points_in_world[i];
    const double depth = p.z();
    const double noisy_depth = bf / (bf / depth + sigma_disp * n(rng));
    p *= noisy_depth / depth;
    f->candidate_sigmas[i] = noisy_depth * noisy_depth * sigma_disp / bf;
  }
}

TEST(Fitter, ShapesLeaveTheMeanUnderStereoNoise) {
  // Cars 2 sigma taller and shorter than the mean (along the component that
  // changes the height most), 21 frames at ~22 m with stereo noise along the
  // ray (0.5 px: sigma_d ~ 0.6 m), 4 % clutter. With the data term weighted
  // by the effective number of observations the fitted height moves from the
  // mean more than half way to the truth (defaults: 41 % of the difference
  // left for the shorter car); weighted as a mean over points (the paper's E)
  // the prior holds the shape near the mean. (With a correlation area of 1 px,
  // i.e. every point independent as the noise here is, the ray-depth term
  // overshot while points without a crossing counted 5 phi: 1.72 m fitted for
  // 1.51 m, 1.35 m for 1.10 m, along-ray +0.22 m; docs/fitting.md, "Known bias".)
  const ShapeLookup lookup(Model());
  const int nr = lookup.num_components();
  const int component = ComponentChangingMost(lookup, 1);
  const double h_mean = Height(lookup, Eigen::VectorXd::Zero(nr));
  for (const double sign : {1.0, -1.0}) {
    Eigen::VectorXd z_true = Eigen::VectorXd::Zero(nr);
    z_true[component] = 2.0 * sign * lookup.sigmas()[component];
    const double h_true = Height(lookup, z_true);
    ASSERT_GT(std::abs(h_true - h_mean), 0.1);
    const Eigen::Vector4d start(-5.0, 1.65, 21.0, 0.7);
    Synthetic s = MakeTrack(lookup, 21, 0.0, 0.0, 1200, 31, -1, &z_true, &start);
    std::mt19937 rng(32);
    std::normal_distribution<double> n(0.0, 1.0);
    for (size_t k = 0; k < s.track.frames.size(); ++k) {
      TrackFrame& f = s.track.frames[k];
      testing::KeepVisible(lookup, z_true, WorldFromObject(s.poses_true[k].head<3>(), s.poses_true[k][3]),
                           Eigen::Vector3d::Zero(), &f.candidate_points_in_world, &f.candidate_sigmas);
    }
    for (TrackFrame& f : s.track.frames) AddDisparityNoise(0.5, n, rng, &f);
    FitOptions options;  // defaults: ray-depth term, mixture, effective weighting (80 px)
    // The stereo evidence alone (MakeTrack's detections carry the true size).
    options.detection_size_sigma = 0.0;
    const TrackFit fit = TrackFitter(Model(), options).Fit(s.track);
    EXPECT_TRUE(fit.summary.usable);
    const double h_fit = Height(lookup, fit.shape_code);
    EXPECT_LT(std::abs(h_fit - h_true), 0.5 * std::abs(h_mean - h_true))
        << "true " << h_true << " mean " << h_mean << " fitted " << h_fit;
    double along = 0.0;
    for (size_t k = 0; k < fit.frames.size(); ++k) {
      const Eigen::Vector3d truth = s.poses_true[k].head<3>();
      along += (fit.frames[k].position - truth).dot(truth.normalized()) / double(fit.frames.size());
    }
    // The origin's offset also carries the part of the shape the prior still
    // holds near the mean (a fitted car smaller than the true one sits with
    // its visible surface on the data and its origin nearer): measured
    // -0.20 m for the taller car, -0.02 m for the shorter one (2026-12-02,
    // the far-side points measured against the first crossing; +0.14 m for
    // the taller car when they counted 5 phi).
    EXPECT_LT(std::abs(along), 0.25) << "along-ray offset (+: away from the camera) " << along
                                     << ", true height " << h_true;
    options.data_weighting = DataWeighting::kMean;
    const TrackFit mean_fit = TrackFitter(Model(), options).Fit(s.track);
    const double h_mean_fit = Height(lookup, mean_fit.shape_code);
    EXPECT_LT(std::abs(h_mean_fit - h_mean), std::abs(h_fit - h_mean))
        << "mean weighting: fitted " << h_mean_fit;
  }
}

TEST(Fitter, DetectedSizesMoveFarShapesTowardsTheTruth) {
  // A car 2 sigma longer than the mean (along the component that changes the
  // length most) at ~34 m, standing, 21 frames; stereo noise of 0.5 px along
  // the ray (sigma_d ~1.5 m) on the visible points; detected sizes with the
  // detector model's error (0.3 m per dimension, AR(1) over 3 frames). The
  // stereo alone leaves the shape near the mean; with the detected sizes the
  // fitted length and size are nearer the truth.
  const ShapeLookup lookup(Model());
  const int nr = lookup.num_components();
  const int component = ComponentChangingMost(lookup, 0);
  Eigen::VectorXd z_true = Eigen::VectorXd::Zero(nr);
  z_true[component] = 2.0 * lookup.sigmas()[component];
  const Eigen::Vector3d size_true = lookup.InsideBox(z_true).Size();
  const double l_mean = lookup.InsideBox(Eigen::VectorXd::Zero(nr)).Size().x();
  ASSERT_GT(std::abs(size_true.x() - l_mean), 0.2);
  const Eigen::Vector4d start(-3.0, 1.65, 34.0, 0.3);
  Synthetic s = MakeTrack(lookup, 21, 0.0, 0.0, 1200, 41, -1, &z_true, &start);
  std::mt19937 rng(42);
  std::normal_distribution<double> n(0.0, 1.0);
  const double rho = std::exp(-1.0 / 3.0);
  Eigen::Vector3d size_error = 0.3 * testing::DrawVector(n, rng);
  for (size_t k = 0; k < s.track.frames.size(); ++k) {
    TrackFrame& f = s.track.frames[k];
    testing::KeepVisible(lookup, z_true, WorldFromObject(s.poses_true[k].head<3>(), s.poses_true[k][3]),
                         Eigen::Vector3d::Zero(), &f.candidate_points_in_world, &f.candidate_sigmas);
    AddDisparityNoise(0.5, n, rng, &f);
    if (k > 0) size_error = rho * size_error + std::sqrt(1.0 - rho * rho) * 0.3 * testing::DrawVector(n, rng);
    f.detection.length = size_true.x() + size_error.x();
    f.detection.height = size_true.y() + size_error.y();
    f.detection.width = size_true.z() + size_error.z();
  }

  FitOptions options;
  const TrackFit with = TrackFitter(Model(), options).Fit(s.track);
  options.detection_size_sigma = 0.0;
  const TrackFit without = TrackFitter(Model(), options).Fit(s.track);
  ASSERT_TRUE(with.summary.usable && without.summary.usable);
  const Eigen::Vector3d size_with = lookup.InsideBox(with.shape_code).Size();
  const Eigen::Vector3d size_without = lookup.InsideBox(without.shape_code).Size();
  const double l_with = std::abs(size_with.x() - size_true.x());
  const double l_without = std::abs(size_without.x() - size_true.x());
  EXPECT_LT(l_with, 0.5 * l_without) << "true length " << size_true.x() << ", mean " << l_mean << ", fitted "
                                     << size_with.x() << " with the detected sizes, " << size_without.x()
                                     << " without";
  EXPECT_LT(l_with, 0.25);
  EXPECT_LT((size_with - size_true).norm(), 0.5 * (size_without - size_true).norm())
      << "true size " << size_true.transpose() << ", fitted " << size_with.transpose() << " with the detected sizes, "
      << size_without.transpose() << " without";
  // (Measured 2026-12-02: length 4.50 / 4.15 m for 4.53 m. The origin does not
  // follow here: +0.21 m along the ray with the sizes, +0.11 m without, the
  // ray-depth term's own offset under 1.5 m depth noise; on the street
  // benchmark the far origins did improve, docs/fitting.md "Detected size".)
}

// The detected positions observe the poses (detection_position_cost.h): a
// track whose detections all lie 0.6 m beside the car fits beside it when
// their covariance is tight, on the car when the term is off or the track
// carries no covariance (hand-made tracks, --no-detection-position).
TEST(Fitter, DetectedPositionsObserveThePoses) {
  FitOptions options;
  TrackFitter fitter(Model(), options);
  Synthetic s = MakeTrack(fitter.lookup(), 6, 0.0, 0.0, 300, 21);
  const Eigen::Vector3d shift(0.6, 0.0, 0.0);
  for (TrackFrame& f : s.track.frames) f.detection.position += shift;
  auto mean_offset = [&](const TrackFit& fit) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < fit.frames.size(); ++k) sum += fit.frames[k].position - s.poses_true[k].head<3>();
    return Eigen::Vector3d(sum / double(fit.frames.size()));
  };
  // No covariance: the stereo points place the car.
  const Eigen::Vector3d without = mean_offset(fitter.Fit(s.track));
  EXPECT_LT(without.norm(), 0.1) << without.transpose();
  // A detector far more precise than the points (0.01 m): the detections win.
  Track tight = s.track;
  for (TrackFrame& f : tight.frames) f.detection_covariance = 1e-4 * Eigen::Matrix3d::Identity();
  const Eigen::Vector3d with = mean_offset(fitter.Fit(tight));
  EXPECT_GT(with.x(), 0.45) << with.transpose();
  EXPECT_LT((with - shift).norm(), 0.15) << with.transpose();
  // Off: the covariance is ignored.
  options.detection_position = false;
  const Eigen::Vector3d off = mean_offset(TrackFitter(Model(), options).Fit(tight));
  EXPECT_LT((off - without).norm(), 1e-6) << off.transpose();
}

TEST(Fitter, OneFrameTrackInJointModeIsTheSingleFrameProblem) {
  // T = 1: no motion term, weights 1/T = 1, so the joint fit and the
  // single-frame fit solve the same problem.
  const ShapeLookup lookup(Model());
  Synthetic s = MakeTrack(lookup, 3, 5.0, 0.0, 300, 14);
  Track one = s.track;
  one.frames.resize(1);
  FitOptions options;
  const TrackFit joint = TrackFitter(Model(), options).Fit(one);
  options.single_frame = true;
  const TrackFit single = TrackFitter(Model(), options).Fit(one);
  ASSERT_EQ(joint.frames.size(), 1u);
  ASSERT_EQ(single.frames.size(), 1u);
  EXPECT_FALSE(joint.single_frame);
  EXPECT_TRUE(joint.summary.usable) << joint.summary.BriefReport();
  EXPECT_EQ(joint.frames[0].motion_model, "none");
  EXPECT_GT(joint.frames[0].num_points, 100);
  EXPECT_LT((joint.frames[0].position - s.poses_true[0].head<3>()).norm(), 0.15);
  EXPECT_LT((joint.frames[0].position - single.frames[0].position).norm(), 1e-4);
  EXPECT_LT(std::abs(WrapAngle(joint.frames[0].yaw - single.frames[0].yaw)), 1e-4);
  EXPECT_LT((joint.shape_code - single.shape_code).cwiseQuotient(lookup.sigmas()).cwiseAbs().maxCoeff(), 1e-3);
}

// A solve Ceres marks not usable makes the whole fit unusable, with the
// solve and Ceres' termination named (samp fit then counts it as failed).
TEST(Fitter, UnusableReasonNamesTheFirstUnusableSolve) {
  TrackFitter fitter(Model(), FitOptions());
  const Synthetic s = MakeTrack(fitter.lookup(), 3, 5.0, 0.0, 50, 13);
  FitSummary summary = fitter.Fit(s.track).summary;
  ASSERT_TRUE(summary.usable) << summary.BriefReport();
  ASSERT_GE(summary.solves.size(), 2u);
  EXPECT_EQ(summary.UnusableReason(), "");
  summary.solves[1].usable = false;
  summary.solves[1].termination = "FAILURE: Residual and Jacobian evaluation failed.";
  const std::string reason = summary.UnusableReason();
  EXPECT_NE(reason.find("solve 2 of " + std::to_string(summary.solves.size()) + " (EM) is not usable"),
            std::string::npos) << reason;
  EXPECT_NE(reason.find("FAILURE: Residual and Jacobian evaluation failed."), std::string::npos) << reason;
  summary.solves[0].usable = false;
  EXPECT_NE(summary.UnusableReason().find("solve 1 of"), std::string::npos);
  EXPECT_NE(FitSummary().UnusableReason(), "");  // no solve: nothing to report as fitted
}

TEST(Fitter, BadTracksThrowWithTheirName) {
  TrackFitter fitter(Model(), FitOptions());
  Synthetic s = MakeTrack(fitter.lookup(), 3, 5.0, 0.0, 50, 13);
  Track none = s.track;
  none.frames.clear();
  try {
    fitter.Fit(none);
    FAIL() << "track without frames accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("track 3"), std::string::npos) << e.what();
  }
  Track empty = s.track;
  for (auto& f : empty.frames) {
    f.candidate_points_in_world.clear();
    f.candidate_sigmas.clear();
  }
  EXPECT_THROW(fitter.Fit(empty), Error);
  Track nan = s.track;
  nan.frames[1].candidate_points_in_world[0].x() = NAN;
  EXPECT_THROW(fitter.Fit(nan), Error);
  Track backwards = s.track;
  backwards.frames[2].time = 0.0;
  EXPECT_THROW(fitter.Fit(backwards), Error);
}


// The real KITTI frame in ../shared/kitti/000046 (one frame, one detected
// car at ~13 m), when present: default options fit it in joint mode.
TEST(FitterRealKitti, OneFrameTrackFitsWithDefaults) {
  const char* env = std::getenv("SAMP_SHARED_DIR");
  const std::string dir = std::string(env != nullptr ? env : SAMP_SHARED_DIR) + "/kitti/000046";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << dir << " not present";
  const std::vector<Track> tracks = LoadSequenceTracks(dir, SequenceOptions());
  ASSERT_EQ(tracks.size(), 1u);
  const ShapeModel model = ShapeModel::Load(SAMP_SHIPPED_MODEL);
  const TrackFitter fitter(model, FitOptions());
  const TrackFit fit = fitter.Fit(tracks[0]);
  EXPECT_TRUE(fit.summary.usable) << fit.summary.BriefReport();
  ASSERT_EQ(fit.frames.size(), 1u);
  EXPECT_GT(fit.frames[0].num_points, 500);
  // Within a metre of the detection (a real detector's box, ~13 m away).
  const TrackFrame& f = tracks[0].frames[0];
  const Eigen::Vector3d detection = f.world_from_camera * f.detection.position;
  EXPECT_LT((fit.frames[0].position - detection).norm(), 1.0);
}

}  // namespace
}  // namespace samp
