// Residuals and analytic Jacobians of the fitter's cost functions, checked
// against numeric differentiation (central differences) and direct formulas.
#include <ceres/cost_function.h>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <iostream>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/data/tracking.h"
#include "libsamp/fit/detection_position_cost.h"
#include "libsamp/fit/detection_size_cost.h"
#include "libsamp/fit/ground_cost.h"
#include "libsamp/fit/motion_cost.h"
#include "libsamp/fit/sdf_cost.h"
#include "libsamp/model/shape_lookup.h"
#include "libsamp/fit/shape_prior_cost.h"
#include "tests/fit/fit_test_util.h"

namespace samp {
namespace {

const ShapeModel& Model() {
  static const ShapeModel model = testing::MakeSyntheticModel(5, 0.1);
  return model;
}
const ShapeLookup& Lookup() {
  static const ShapeLookup lookup(Model());
  return lookup;
}

// Analytic Jacobians vs central differences (step 1e-6, absolute), entry by
// entry: |analytic - numeric| <= tolerance * max(1, |numeric|). (Own central
// differences rather than ceres::GradientChecker, whose relative step is
// scaled by |x| and so too coarse for world coordinates of ~15 m on a 0.1 m
// piecewise-trilinear field.)
void ExpectJacobiansMatch(const ceres::CostFunction& cost, std::vector<double*> params,
                          double tolerance, const std::string& what) {
  const int num_residuals = cost.num_residuals();
  const std::vector<int32_t>& sizes = cost.parameter_block_sizes();
  ASSERT_EQ(sizes.size(), params.size());
  std::vector<std::vector<double>> jacobians(sizes.size());
  std::vector<double*> jacobian_ptrs(sizes.size());
  for (size_t b = 0; b < sizes.size(); ++b) {
    jacobians[b].assign(size_t(num_residuals) * sizes[b], 0.0);
    jacobian_ptrs[b] = jacobians[b].data();
  }
  std::vector<double> r0(num_residuals), rp(num_residuals), rm(num_residuals);
  ASSERT_TRUE(cost.Evaluate(params.data(), r0.data(), jacobian_ptrs.data())) << what;
  int bad = 0;
  double worst = 0.0;
  std::ostringstream log;
  for (size_t b = 0; b < sizes.size(); ++b) {
    for (int k = 0; k < sizes[b]; ++k) {
      const double h = 1e-6, saved = params[b][k];
      params[b][k] = saved + h;
      ASSERT_TRUE(cost.Evaluate(params.data(), rp.data(), nullptr));
      params[b][k] = saved - h;
      ASSERT_TRUE(cost.Evaluate(params.data(), rm.data(), nullptr));
      params[b][k] = saved;
      for (int i = 0; i < num_residuals; ++i) {
        const double numeric = (rp[i] - rm[i]) / (2 * h);
        const double analytic = jacobians[b][size_t(i) * sizes[b] + k];
        const double error = std::abs(analytic - numeric) / std::max(1.0, std::abs(numeric));
        worst = std::max(worst, error);
        if (error > tolerance) {
          if (bad < 5) log << " block " << b << " row " << i << " col " << k << ": " << analytic << " vs " << numeric << "\n";
          ++bad;
        }
      }
    }
  }
  EXPECT_EQ(bad, 0) << what << ": worst error " << worst << "\n" << log.str();
}

TEST(SdfCost, HuberPsi) {
  double d;
  EXPECT_DOUBLE_EQ(SdfCost::Psi(0.5, 1.0, &d), 0.5);
  EXPECT_DOUBLE_EQ(d, 1.0);
  // psi^2 = 2 k |s| - k^2 outside.
  EXPECT_NEAR(SdfCost::Psi(3.0, 1.0, &d), std::sqrt(5.0), 1e-15);
  EXPECT_NEAR(d, 1.0 / std::sqrt(5.0), 1e-15);
  EXPECT_NEAR(SdfCost::Psi(-3.0, 1.0, &d), -std::sqrt(5.0), 1e-15);
  // C^1 at the threshold.
  double d1, d2;
  EXPECT_NEAR(SdfCost::Psi(1.0 - 1e-9, 1.0, &d1), SdfCost::Psi(1.0 + 1e-9, 1.0, &d2), 1e-8);
  EXPECT_NEAR(d1, d2, 1e-8);
}

struct SdfCase {
  double yaw;
  double huber;
  double offset;  // pushes points away from the surface / out of the grid
};

TEST(SdfCost, ResidualAndJacobians) {
  const ShapeLookup& lookup = Lookup();
  std::mt19937 rng(3);
  const Eigen::VectorXd z_true = 0.5 * lookup.sigmas();
  const std::vector<Eigen::Vector3d> surface = testing::SampleSurface(lookup, z_true, 60, &rng);
  ASSERT_EQ(surface.size(), 60u);
  std::normal_distribution<double> n(0.0, 1.0);
  const SdfCase cases[] = {{0.3, 1.0, 0.05},       {M_PI - 1e-6, 1.0, 0.1}, {-M_PI + 1e-6, 0.5, 0.2},
                           {-1.4, 0.2, 0.3},        {M_PI, 1.0, 3.0},        {2.0, 1.0, 5.0}};
  for (const SdfCase& c : cases) {
    const Eigen::Vector3d t(4.0, 1.6, 15.0);
    const Eigen::Isometry3d world_from_object = WorldFromObject(t, c.yaw);
    std::vector<Eigen::Vector3d> points;
    std::vector<double> sigmas;
    for (const auto& p : surface) {
      const Eigen::Vector3d noise = testing::DrawVector(n, rng);
      points.push_back(world_from_object * (p + c.offset * noise));
      sigmas.push_back(0.1 + 0.05 * std::abs(n(rng)));
    }
    const double weight = 1.0 / 7.0;
    SdfCost cost(&lookup, points, sigmas, c.huber, weight);
    Eigen::VectorXd z = 0.3 * lookup.sigmas();
    double pose[4] = {t.x() + 0.05, t.y() - 0.02, t.z() + 0.03, c.yaw + 0.01};
    // Residuals agree with the definition.
    std::vector<double> residuals(points.size());
    const double* params[2] = {z.data(), pose};
    ASSERT_TRUE(cost.Evaluate(params, residuals.data(), nullptr));
    double energy = 0, expected = 0;
    int outside = 0;
    const Eigen::Isometry3d object_from_world =
        ObjectFromWorld(Eigen::Vector3d(pose[0], pose[1], pose[2]), pose[3]);
    for (size_t i = 0; i < points.size(); ++i) {
      energy += residuals[i] * residuals[i];
      const Eigen::Vector3d o = object_from_world * points[i];
      const Eigen::Vector3d lo = lookup.grid().MinCorner(), hi = lookup.grid().MaxCorner();
      outside += ((o.array() < lo.array()) || (o.array() > hi.array())).any();
      const double s = lookup.Evaluate(z, o) / sigmas[i];
      const double rho = std::abs(s) <= c.huber ? s * s : 2 * c.huber * std::abs(s) - c.huber * c.huber;
      expected += weight / points.size() * rho;
    }
    EXPECT_NEAR(energy, expected, 1e-9 * std::max(1.0, expected));
    if (c.offset >= 3.0) {
      EXPECT_GT(outside, 10) << "case must exercise points outside the grid";
    }
    ExpectJacobiansMatch(cost, {z.data(), pose}, 1e-6,
                         "yaw " + std::to_string(c.yaw) + " offset " + std::to_string(c.offset));
  }
}

// Distance from o along unit direction dir to the first sign change of phi_z,
// by fine stepping (reference for the ray distance).
double BruteForceRayDistance(const ShapeLookup& lookup, const Eigen::VectorXd& z, const Eigen::Vector3d& o,
                             const Eigen::Vector3d& dir, double max_distance) {
  const double phi_o = lookup.Evaluate(z, o);
  const double step = 1e-4;
  for (double d = step; d <= max_distance; d += step) {
    const double v = lookup.Evaluate(z, Eigen::Vector3d(o + d * dir));
    if ((v < 0.0) != (phi_o < 0.0)) {
      const double v0 = lookup.Evaluate(z, Eigen::Vector3d(o + (d - step) * dir));
      return d - step + step * v0 / (v0 - v);
    }
  }
  return -1.0;  // no crossing
}

TEST(SdfCost, RayDistanceResidualsAndJacobians) {
  const ShapeLookup& lookup = Lookup();
  std::mt19937 rng(8);
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::VectorXd z_true = 0.5 * lookup.sigmas();
  const auto surface = testing::SampleSurface(lookup, z_true, 80, &rng);
  const Eigen::Vector3d camera(1.0, -0.3, 2.0);
  // Huber and the mixture robustifier (mixture_loss), threshold 2 sigma each.
  for (const bool mixture : {false, true})
  for (const double yaw : {0.4, M_PI - 1e-6, -2.0}) {
    const Eigen::Vector3d t(4.0, 1.6, 15.0);
    const Eigen::Isometry3d world_from_object = WorldFromObject(t, yaw);
    std::vector<Eigen::Vector3d> points;
    std::vector<double> sigmas;
    for (const auto& p : surface) {
      // Noise along the viewing ray, as stereo; a few points off to the side.
      const Eigen::Vector3d w = world_from_object * p;
      const Eigen::Vector3d ray = (w - camera).normalized();
      const Eigen::Vector3d jitter = testing::DrawVector(n, rng);  // drawn first, as GCC did
      const double along = n(rng);
      points.push_back(w + 0.4 * along * ray + 0.05 * jitter);
      sigmas.push_back(0.1 + 0.05 * std::abs(n(rng)));
    }
    SdfCostOptions options;
    options.huber_threshold = 2.0;
    options.weight = 0.25;
    options.term = DataTerm::kRayDepth;
    options.camera_in_world = camera;
    options.mixture_loss = mixture;
    options.outlier_threshold = 2.0;
    SdfCost cost(&lookup, points, sigmas, options);
    Eigen::VectorXd z = 0.3 * lookup.sigmas();
    double pose[4] = {t.x() + 0.05, t.y() - 0.02, t.z() + 0.03, yaw + 0.01};
    std::vector<double> residuals(points.size());
    const double* params[2] = {z.data(), pose};
    ASSERT_TRUE(cost.Evaluate(params, residuals.data(), nullptr));
    // Residuals: the signed distance along the ray (towards the camera from
    // inside, away from it outside) when it reaches the surface within 5 |phi|;
    // else, for a point behind the far side, minus its depth behind the
    // first crossing from the camera; else the Euclidean phi (the paper's).
    const Eigen::Isometry3d object_from_world = ObjectFromWorld(Eigen::Vector3d(pose[0], pose[1], pose[2]), pose[3]);
    const Eigen::Vector3d camera_in_object = object_from_world * camera;
    int num_inside = 0, num_hits = 0, num_behind = 0, num_skipped = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector3d o = object_from_world * points[i];
      const Eigen::Vector3d u = object_from_world.linear() * (points[i] - camera).normalized();
      const double phi = lookup.Evaluate(z, o);
      num_inside += phi < 0.0;
      const double d = BruteForceRayDistance(lookup, z, o, phi < 0.0 ? Eigen::Vector3d(-u) : u, 5 * std::abs(phi));
      num_hits += d >= 0.0;
      double expected_phi = d >= 0.0 ? (phi < 0.0 ? -d : d) : phi;
      if (d < 0.0 && phi > 0.0) {
        // The first crossing from the camera, marched from 12 m before the
        // point (the car and the noise lie well within that).
        const double li = (o - camera_in_object).norm();
        const double start = li - 12.0;
        const double first = BruteForceRayDistance(lookup, z, camera_in_object + start * u, u, 12.0);
        if (first >= 0.0 && start + first < li) {
          // A crossing at a grazing angle counts as a miss in the cost (its
          // slope test uses the unnormalised gradient): skipped here.
          Eigen::Vector3d g;
          lookup.Evaluate(z, Eigen::Vector3d(camera_in_object + (start + first) * u), &g);
          if (g.normalized().dot(u) > -0.15) {
            ++num_skipped;
            continue;
          }
          expected_phi = -(li - (start + first));
          ++num_behind;
        }
      }
      const double scaled = expected_phi / sigmas[i];
      const double expected = std::sqrt(options.weight / points.size()) *
                              (mixture ? SdfCost::MixturePsi(scaled, options.outlier_threshold, nullptr)
                                       : SdfCost::Psi(scaled, options.huber_threshold, nullptr));
      EXPECT_NEAR(residuals[i], expected, 2e-3 * std::abs(expected) + 1e-5) << "point " << i << " phi " << phi;
      EXPECT_GE(std::abs(expected_phi), std::abs(phi) - 1e-3) << "the ray distance is at least |phi|";
    }
    EXPECT_GT(num_inside, 15);
    EXPECT_GT(num_hits, 10);  // both paths: rays that reach the surface within 5 |phi| and rays that do not
    EXPECT_GT(int(points.size()) - num_hits - num_behind, 5);  // rays that pass the shape
    EXPECT_GT(num_behind, 3);  // points behind the far side
    EXPECT_LE(num_skipped, 8);  // of 80
    ExpectJacobiansMatch(cost, {z.data(), pose}, 1e-5,
                         std::string(mixture ? "mixture" : "Huber") + " ray distance, yaw " + std::to_string(yaw));
  }
  SdfCostOptions bad;
  bad.term = DataTerm::kRayDepth;
  bad.camera_in_world = Eigen::Vector3d(4.0, 1.6, 15.0);
  EXPECT_THROW(SdfCost(&lookup, {Eigen::Vector3d(4.0, 1.6, 15.0)}, {0.1}, bad), Error);
}

TEST(SdfCost, MixturePsi) {
  // psi^2 = rho = -2 log((exp(-s^2/2) + c) / (1 + c)), c = exp(-s0^2/2).
  const double s0 = 3.0, c = std::exp(-4.5);
  for (double s : {-7.0, -3.0, -1.0, -1e-6, 0.0, 1e-8, 0.3, 2.0, 3.0, 10.0}) {
    double d;
    const double psi = SdfCost::MixturePsi(s, s0, &d);
    const double rho = -2.0 * std::log((std::exp(-0.5 * s * s) + c) / (1.0 + c));
    EXPECT_NEAR(psi * psi, rho, 1e-12 * std::max(1.0, rho)) << s;
    EXPECT_GE(psi * s, 0.0);
    const double h = 1e-6;
    if (std::abs(s) > 1e-5) {
      const double numeric = (SdfCost::MixturePsi(s + h, s0, nullptr) - SdfCost::MixturePsi(s - h, s0, nullptr)) / (2 * h);
      EXPECT_NEAR(d, numeric, 1e-6 * std::max(1.0, std::abs(numeric))) << s;
    } else {
      EXPECT_NEAR(d, 1.0 / std::sqrt(1.0 + c), 1e-9);
    }
  }
  // Bounded: clutter far from the surface adds at most rho_max.
  const double rho_max = -2.0 * std::log(c / (1.0 + c));
  EXPECT_NEAR(std::pow(SdfCost::MixturePsi(50.0, s0, nullptr), 2), rho_max, 1e-9);
  EXPECT_LT(std::pow(SdfCost::MixturePsi(2.0, s0, nullptr), 2), 0.5 * rho_max);
}

// First crossing of the ray camera + lambda u (object frame) with phi_z < 0
// by fine stepping over [0, 60] m; the smallest phi along it when none.
struct BruteRay {
  bool hit = false;
  double lambda = 0.0;
  double phi_min = 1e9;
};
BruteRay BruteForceFirstCrossing(const ShapeLookup& lookup, const Eigen::VectorXd& z, const Eigen::Vector3d& cam,
                                 const Eigen::Vector3d& u, double lambda_point) {
  BruteRay out;
  const double step = 2e-4;
  double prev = lookup.Evaluate(z, Eigen::Vector3d(cam + (lambda_point - 8.0) * u));
  for (double l = lambda_point - 8.0 + step; l <= lambda_point + 8.0; l += step) {
    const double v = lookup.Evaluate(z, Eigen::Vector3d(cam + l * u));
    out.phi_min = std::min(out.phi_min, v);
    if (v < 0.0 && prev >= 0.0) {
      out.hit = true;
      out.lambda = l - step + step * prev / (prev - v);
      return out;
    }
    prev = v;
  }
  return out;
}

TEST(SdfCost, DisparityResidualsAndJacobians) {
  const ShapeLookup& lookup = Lookup();
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::VectorXd z_true = 0.5 * lookup.sigmas();
  const Eigen::Vector3d camera(1.0, -0.3, 2.0);
  const Eigen::Vector3d axis = Eigen::Vector3d(0.05, 0.0, 1.0).normalized();
  for (const double yaw : {0.4, M_PI - 1e-6, -2.0, -M_PI + 1e-6}) {
    const Eigen::Vector3d t(4.0, 1.6, 15.0);
    const Eigen::Isometry3d world_from_object = WorldFromObject(t, yaw);
    const Eigen::Vector3d view = world_from_object.inverse() * camera - Eigen::Vector3d(0, -0.7, 0);
    const auto surface = testing::SampleSurface(lookup, z_true, 120, &rng, view.normalized());
    std::vector<Eigen::Vector3d> points;
    std::vector<double> sigmas;
    for (const auto& p : surface) {
      // Stereo-like noise along the ray; some clutter beside the car.
      const Eigen::Vector3d w = world_from_object * p;
      const Eigen::Vector3d ray = (w - camera).normalized();
      const Eigen::Vector3d jitter = testing::DrawVector(n, rng);  // drawn first, as GCC did
      const double along = n(rng);
      points.push_back(w + 0.5 * along * ray + 0.1 * jitter);
      sigmas.push_back(0.2 + 0.05 * std::abs(n(rng)));
    }
    for (int i = 0; i < 30; ++i) {
      const Eigen::Vector3d clutter = testing::DrawVector(n, rng);
      points.push_back(world_from_object *
                       Eigen::Vector3d(3.0 * clutter.x(), -0.8 + 0.6 * clutter.y(), 2.5 * clutter.z()));
      sigmas.push_back(0.3);
    }
    SdfCostOptions options;
    options.weight = 3.0;
    options.term = DataTerm::kDisparity;
    options.camera_in_world = camera;
    options.camera_axis_in_world = axis;
    options.focal_px = 700.0;
    options.silhouette_sigma_px = 2.0;
    options.outlier_threshold = 3.0;
    SdfCost cost(&lookup, points, sigmas, options);
    Eigen::VectorXd z = 0.3 * lookup.sigmas();
    double pose[4] = {t.x() + 0.05, t.y() - 0.02, t.z() + 0.03, yaw + 0.01};
    std::vector<double> residuals(points.size());
    const double* params[2] = {z.data(), pose};
    ASSERT_TRUE(cost.Evaluate(params, residuals.data(), nullptr));
    const std::vector<RayResidual> rays = cost.RayResiduals(z.data(), pose);
    const Eigen::Isometry3d object_from_world =
        ObjectFromWorld(Eigen::Vector3d(pose[0], pose[1], pose[2]), pose[3]);
    const Eigen::Vector3d cam_o = object_from_world * camera;
    int num_hits = 0, num_misses = 0, agree = 0, mismatches = 0;
    std::vector<bool> is_hit(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      const double lambda_i = (points[i] - camera).norm();
      const Eigen::Vector3d u = object_from_world.linear() * (points[i] - camera).normalized();
      const BruteRay b = BruteForceFirstCrossing(lookup, z, cam_o, u, lambda_i);
      is_hit[i] = rays[i].hit;
      if (b.hit != rays[i].hit) continue;  // grazing rays may disagree
      ++agree;
      if (rays[i].grazing) continue;
      const double a = (points[i] - camera).normalized().dot(axis);
      double expected_s;
      if (b.hit) {
        ++num_hits;
        expected_s = a * lambda_i * (b.lambda - lambda_i) / (b.lambda * sigmas[i]);
        // The disparity error: b f (1/z_i - 1/z_s) / sigma_disp with sigma_d = z_i^2 sigma_disp / (b f).
        const double bf = 400.0, sigma_disp = sigmas[i] * bf / std::pow(a * lambda_i, 2);
        EXPECT_NEAR(expected_s, bf * (1.0 / (a * lambda_i) - 1.0 / (a * b.lambda)) / sigma_disp, 1e-9);
      } else {
        ++num_misses;
        expected_s = b.phi_min * 700.0 / (a * lambda_i * 2.0);
        // Far misses (rays past the grid box; saturated by the mixture) are
        // measured at the closest approach to the box centre instead.
        if (expected_s > 6.0) continue;
      }
      const double expected = std::sqrt(options.weight / points.size()) * SdfCost::MixturePsi(expected_s, 3.0, nullptr);
      // (Sphere tracing steps at least half a voxel: a ray that only grazes
      // a sliver of the shape may pass it.)
      if (std::abs(rays[i].value - expected_s) > 2e-3 * std::abs(expected_s) + 2e-3 ||
          std::abs(residuals[i] - expected) > 2e-3 * std::abs(expected) + 1e-4) {
        ++mismatches;
      }
    }
    EXPECT_GE(agree, int(points.size()) * 95 / 100);
    EXPECT_LE(mismatches, 2) << "yaw " << yaw;
    EXPECT_GT(num_hits, 50);
    EXPECT_GT(num_misses, 15);
    // Jacobians vs central differences: hits exactly (implicit
    // differentiation of the crossing), misses by the envelope theorem at
    // the refined closest approach (looser; a few rows may switch between
    // hit and miss or between sampled minima within the step).
    const int nr = lookup.num_components(), rows = cost.num_residuals();
    std::vector<double> jz(size_t(rows) * nr), jp(size_t(rows) * 4);
    double* jac[2] = {jz.data(), jp.data()};
    std::vector<double> r0(rows), rp(rows), rm(rows);
    ASSERT_TRUE(cost.Evaluate(params, r0.data(), jac));
    int bad_hits = 0, bad_misses = 0;
    double* blocks[2] = {z.data(), pose};
    const int sizes[2] = {nr, 4};
    for (int b = 0; b < 2; ++b) {
      for (int k = 0; k < sizes[b]; ++k) {
        const double h = 1e-6, saved = blocks[b][k];
        blocks[b][k] = saved + h;
        ASSERT_TRUE(cost.Evaluate(params, rp.data(), nullptr));
        blocks[b][k] = saved - h;
        ASSERT_TRUE(cost.Evaluate(params, rm.data(), nullptr));
        blocks[b][k] = saved;
        for (int i = 0; i < rows; ++i) {
          const double numeric = (rp[i] - rm[i]) / (2 * h);
          const double analytic = b == 0 ? jz[size_t(i) * nr + k] : jp[size_t(i) * 4 + k];
          const double error = std::abs(analytic - numeric) / std::max(1.0, std::abs(numeric));
          if (rays[i].hit && !rays[i].grazing) bad_hits += error > 1e-5;
        }
      }
    }
    // Misses: against central differences of the true closest approach
    // (brute-force minimum of phi along the ray, 10 um steps near lambda*), on
    // the rays passing within 6 silhouette sigmas (the rest is saturated).
    int checked = 0, pose_entries = 0;
    for (int i = 0; i < rows && checked < 12; ++i) {
      if (rays[i].hit || rays[i].value > 6.0) continue;
      ++checked;
      auto brute_residual = [&]() {
        const Eigen::Isometry3d ofw = ObjectFromWorld(Eigen::Vector3d(pose[0], pose[1], pose[2]), pose[3]);
        const Eigen::Vector3d co = ofw * camera;
        const Eigen::Vector3d u = ofw.linear() * (points[i] - camera).normalized();
        const double lambda_i = (points[i] - camera).norm();
        double best = 1e9;
        for (double l = lambda_i - 4.0; l < lambda_i + 4.0; l += 1e-3) {
          best = std::min(best, lookup.Evaluate(z, Eigen::Vector3d(co + l * u)));
        }
        // Refine around the coarse minimum.
        double lb = 0.0;
        for (double l = lambda_i - 4.0; l < lambda_i + 4.0; l += 1e-3) {
          if (lookup.Evaluate(z, Eigen::Vector3d(co + l * u)) == best) lb = l;
        }
        for (double l = lb - 2e-3; l < lb + 2e-3; l += 1e-5) {
          best = std::min(best, lookup.Evaluate(z, Eigen::Vector3d(co + l * u)));
        }
        const double a = (points[i] - camera).normalized().dot(axis);
        const double s_i = best * 700.0 / (a * lambda_i * 2.0);
        return std::sqrt(options.weight / points.size()) * SdfCost::MixturePsi(s_i, 3.0, nullptr);
      };
      for (int b = 0; b < 2; ++b) {
        for (int k = 0; k < sizes[b]; ++k) {
          const double h = 1e-4, saved = blocks[b][k];
          blocks[b][k] = saved + h;
          const double plus = brute_residual();
          blocks[b][k] = saved - h;
          const double minus = brute_residual();
          blocks[b][k] = saved;
          const double numeric = (plus - minus) / (2 * h);
          const double analytic = b == 0 ? jz[size_t(i) * nr + k] : jp[size_t(i) * 4 + k];
          const double error = std::abs(analytic - numeric) / std::max(0.05, std::abs(numeric));
          if (b == 0) {
            EXPECT_LT(error, 5e-2) << "miss row " << i << " col " << k << ": " << analytic << " vs " << numeric;
          } else {
            ++pose_entries;
            bad_misses += error > 0.25;
          }
        }
      }
    }
    EXPECT_GE(checked, 5);
    EXPECT_LE(bad_hits, 2) << "yaw " << yaw;
    // Shape code: exact (envelope theorem; the closest approach's position
    // does not depend on z). Pose: exact where the closest approach lies
    // inside a voxel; where it sits on a voxel face (a kink of the trilinear
    // field) the derivative omits the face's motion along the ray, so only
    // most entries agree.
    EXPECT_LE(bad_misses, pose_entries / 2) << "yaw " << yaw;
  }
  SdfCostOptions bad;
  bad.term = DataTerm::kDisparity;
  bad.focal_px = 0.0;
  EXPECT_THROW(SdfCost(&lookup, {Eigen::Vector3d(4.0, 1.6, 15.0)}, {0.1}, bad), Error);
  bad.focal_px = 700.0;
  EXPECT_THROW(SdfCost(&lookup, {Eigen::Vector3d(4.0, 1.6, -15.0)}, {0.1}, bad), Error);  // behind the camera
  EXPECT_EQ(ParseDataTerm("disparity"), DataTerm::kDisparity);
  EXPECT_EQ(std::string(DataTermName(ParseDataTerm("ray-depth"))), "ray-depth");
  EXPECT_THROW(ParseDataTerm("sdf"), Error);
}

TEST(CompressedSdfCost, SameCostGradientAndGaussNewtonMatrix) {
  const ShapeLookup& lookup = Lookup();
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::VectorXd z_true = 0.5 * lookup.sigmas();
  const auto surface = testing::SampleSurface(lookup, z_true, 300, &rng);
  for (const DataTerm term : {DataTerm::kPaper, DataTerm::kRayDepth, DataTerm::kDisparity})
  for (double offset : {0.05, 0.5, 4.0}) {  // last: many points outside the grid
    const bool ray = term != DataTerm::kPaper;
    SdfCostOptions options;
    options.weight = 0.2;
    options.term = term;
    options.focal_px = 700.0;
    const Eigen::Isometry3d world_from_object = WorldFromObject(Eigen::Vector3d(3, 1.6, 12), M_PI - 0.01);
    std::vector<Eigen::Vector3d> points;
    std::vector<double> sigmas;
    for (const auto& p : surface) {
      points.push_back(world_from_object * (p + offset * testing::DrawVector(n, rng)));
      sigmas.push_back(0.1);
    }
    SdfCost full(&lookup, points, sigmas, options);
    CompressedSdfCost compressed(&lookup, points, sigmas, options);
    ASSERT_EQ(compressed.num_residuals(), 10);
    Eigen::VectorXd z = -0.2 * lookup.sigmas();
    double pose[4] = {3.1, 1.55, 12.05, -M_PI + 0.02};
    const double* params[2] = {z.data(), pose};
    using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    const int n_full = full.num_residuals();
    Eigen::VectorXd rf(n_full), rc(10), rc_cost(10);
    RowMatrix jzf(n_full, 5), jpf(n_full, 4), jzc(10, 5), jpc(10, 4);
    double* jf[2] = {jzf.data(), jpf.data()};
    double* jc[2] = {jzc.data(), jpc.data()};
    ASSERT_TRUE(full.Evaluate(params, rf.data(), jf));
    ASSERT_TRUE(compressed.Evaluate(params, rc.data(), jc));
    ASSERT_TRUE(compressed.Evaluate(params, rc_cost.data(), nullptr));
    RowMatrix af(n_full, 9), ac(10, 9);
    af << jzf, jpf;
    ac << jzc, jpc;
    const double scale = std::max(1.0, rf.squaredNorm());
    EXPECT_NEAR(rc.squaredNorm(), rf.squaredNorm(), 1e-9 * scale) << "offset " << offset << " ray " << ray;
    EXPECT_NEAR(rc_cost.squaredNorm(), rf.squaredNorm(), 1e-9 * scale);
    const Eigen::VectorXd gf = af.transpose() * rf, gc = ac.transpose() * rc;
    EXPECT_LT((gf - gc).cwiseAbs().maxCoeff(), 1e-8 * std::max(1.0, gf.cwiseAbs().maxCoeff()));
    const Eigen::MatrixXd hf = af.transpose() * af, hc = ac.transpose() * ac;
    EXPECT_LT((hf - hc).cwiseAbs().maxCoeff(), 1e-8 * std::max(1.0, hf.cwiseAbs().maxCoeff()));
    // The linearised cost agrees for an arbitrary step.
    Eigen::VectorXd d(9);
    d << 0.1, -0.2, 0.3, 0.0, 0.05, 0.02, -0.01, 0.03, 0.01;
    EXPECT_NEAR((af * d + rf).squaredNorm(), (ac * d + rc).squaredNorm(), 1e-8 * scale);
  }
}

TEST(CompressedSdfCost, CachedLinearisationFollowsTheParameters) {
  // Every evaluation linearises and keeps the result for its parameters: a
  // cost-only call followed by a Jacobian call at the same parameters, and
  // calls alternating between parameters, must give what a fresh block gives.
  const ShapeLookup& lookup = Lookup();
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0.0, 1.0);
  const auto surface = testing::SampleSurface(lookup, 0.5 * lookup.sigmas(), 200, &rng);
  const Eigen::Isometry3d world_from_object = WorldFromObject(Eigen::Vector3d(3, 1.6, 12), 0.3);
  std::vector<Eigen::Vector3d> points;
  for (const auto& p : surface) points.push_back(world_from_object * (p + 0.05 * testing::DrawVector(n, rng)));
  const std::vector<double> sigmas(points.size(), 0.1);
  using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  struct Result {
    Eigen::VectorXd r = Eigen::VectorXd(10);
    RowMatrix jz = RowMatrix(10, 5), jp = RowMatrix(10, 4);
  };
  auto evaluate = [](const CompressedSdfCost& cost, const Eigen::VectorXd& z, const double* pose, bool jacobians) {
    Result out;
    const double* params[2] = {z.data(), pose};
    double* j[2] = {out.jz.data(), out.jp.data()};
    EXPECT_TRUE(cost.Evaluate(params, out.r.data(), jacobians ? j : nullptr));
    return out;
  };
  const Eigen::VectorXd z1 = 0.2 * lookup.sigmas(), z2 = -0.1 * lookup.sigmas();
  const double pose1[4] = {3.05, 1.6, 12.02, 0.31}, pose2[4] = {2.95, 1.62, 11.97, 0.28};
  const CompressedSdfCost fresh1(&lookup, points, sigmas, 1.0, 0.5), fresh2(&lookup, points, sigmas, 1.0, 0.5);
  const Result expected1 = evaluate(fresh1, z1, pose1, true), expected2 = evaluate(fresh2, z2, pose2, true);
  const CompressedSdfCost cost(&lookup, points, sigmas, 1.0, 0.5);
  const Result cost_only = evaluate(cost, z1, pose1, false);
  EXPECT_EQ(cost_only.r, expected1.r);
  const Result with_jacobians = evaluate(cost, z1, pose1, true);
  EXPECT_EQ(with_jacobians.r, expected1.r);
  EXPECT_EQ(with_jacobians.jz, expected1.jz);
  EXPECT_EQ(with_jacobians.jp, expected1.jp);
  const Result other = evaluate(cost, z2, pose2, true);
  EXPECT_EQ(other.r, expected2.r);
  EXPECT_EQ(other.jp, expected2.jp);
  EXPECT_NE(other.r, expected1.r);
  const double pose1_moved[4] = {pose1[0], pose1[1], pose1[2], pose1[3] + 1e-9};
  EXPECT_NE(evaluate(cost, z1, pose1_moved, false).r, expected1.r) << "a changed pose must not hit the cache";
  EXPECT_EQ(evaluate(cost, z1, pose1, true).jz, expected1.jz);
}

TEST(SdfCost, RejectsBadInput) {
  const ShapeLookup& lookup = Lookup();
  EXPECT_THROW(SdfCost(&lookup, {}, {}, 1.0, 1.0), Error);
  EXPECT_THROW(SdfCost(&lookup, {Eigen::Vector3d(0, 0, 1)}, {0.0}, 1.0, 1.0), Error);
  EXPECT_THROW(SdfCost(&lookup, {Eigen::Vector3d(NAN, 0, 1)}, {0.1}, 1.0, 1.0), Error);
}

TEST(MotionCost, ResidualWrapsYawAndJacobiansMatch) {
  MotionNoise noise;
  const MotionModel models[] = {MotionModel::kStanding, MotionModel::kStraight, MotionModel::kArc};
  for (MotionModel model : models) {
    for (double omega : {0.0, 1e-8, 0.35}) {
      double prev_pose[4] = {2.0, 1.6, 20.0, M_PI - 0.01}, prev_vel[2] = {6.0, omega};
      double pred[6];
      PredictMotion(model, prev_pose, prev_vel, 0.1, pred, nullptr, nullptr);
      // Current yaw on the other side of +-pi: the wrapped difference is small.
      double pose[4] = {pred[0] + 0.1, pred[1], pred[2] - 0.05, WrapAngle(pred[3] + 0.02)};
      double vel[2] = {pred[4] + 0.3, pred[5] - 0.01};
      const auto sigma = MotionCovariance(model, prev_pose, prev_vel, 0.1, noise);
      const auto l = SqrtInformation(sigma);
      MotionCost cost(model, 0.1, l, 0.25);
      double r[6];
      const double* params[4] = {prev_pose, prev_vel, pose, vel};
      ASSERT_TRUE(cost.Evaluate(params, r, nullptr));
      Eigen::Matrix<double, 6, 1> e;
      e << 0.1, 0.0, -0.05, 0.02, 0.3, -0.01;
      const Eigen::Matrix<double, 6, 1> expected = 0.5 * l * e;
      for (int k = 0; k < 6; ++k) EXPECT_NEAR(r[k], expected[k], 1e-9) << MotionModelName(model);
      ExpectJacobiansMatch(cost, {prev_pose, prev_vel, pose, vel}, 1e-6,
                           std::string("motion ") + MotionModelName(model));
    }
  }
}

TEST(GroundCost, ResidualAndJacobian) {
  const Eigen::Vector4d plane = Eigen::Vector4d(0.02, -0.999, 0.03, 1.7).normalized();
  const Eigen::Vector4d unit_plane = plane / plane.head<3>().norm();
  GroundCost cost(unit_plane, 0.1, 0.5);
  double pose[4] = {1.0, 1.2, 10.0, 0.4};
  double r;
  const double* params[1] = {pose};
  ASSERT_TRUE(cost.Evaluate(params, &r, nullptr));
  const double height = unit_plane.head<3>().dot(Eigen::Vector3d(1.0, 1.2, 10.0)) + unit_plane[3];
  EXPECT_NEAR(r, std::sqrt(0.5) * height / 0.1, 1e-12);
  ExpectJacobiansMatch(cost, {pose}, 1e-7, "ground");
}

TEST(DetectionPositionCost, ResidualAndJacobian) {
  // The detector noise model's covariance of a box 30 m away, 25 deg off the
  // optical axis, turned into a world frame yawed by 0.3 rad.
  const Eigen::Vector3d in_camera(30 * std::sin(0.44), 1.6, 30 * std::cos(0.44));
  const Eigen::Matrix3d cov_camera = DetectionCovariance(in_camera, TrackerOptions());
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Matrix3d cov = r * cov_camera * r.transpose();
  const Eigen::Vector3d detected = r * in_camera + Eigen::Vector3d(2, 0, -1);
  // Along the horizontal ray the model's sigma is 0.25 + 0.015 * 30 m = 0.70 m.
  const Eigen::Vector3d ray = Eigen::Vector3d(in_camera.x(), 0, in_camera.z()).normalized();
  EXPECT_NEAR(std::sqrt(ray.dot(cov_camera * ray)), 0.25 + 0.015 * 30.0, 1e-9);
  DetectionPositionCost cost(detected, cov, 0.4);
  double pose[4] = {detected.x() + 0.5, detected.y() - 0.1, detected.z() + 0.7, 1.1};
  double res[3];
  const double* params[1] = {pose};
  ASSERT_TRUE(cost.Evaluate(params, res, nullptr));
  const Eigen::Vector3d d(0.5, -0.1, 0.7);
  // |r|^2 = w (t - p)^T Sigma^-1 (t - p); the yaw does not enter.
  EXPECT_NEAR(Eigen::Map<Eigen::Vector3d>(res).squaredNorm(), 0.4 * d.dot(cov.inverse() * d), 1e-9);
  ExpectJacobiansMatch(cost, {pose}, 1e-7, "detection position");
  // A step along the ray costs less than the same step across it.
  double along[4] = {detected.x(), detected.y(), detected.z(), 0}, across[4] = {detected.x(), detected.y(), detected.z(), 0};
  const Eigen::Vector3d ray_world = r * ray, across_world = r * Eigen::Vector3d(ray.z(), 0, -ray.x());
  for (int a = 0; a < 3; ++a) along[a] += 0.5 * ray_world[a], across[a] += 0.5 * across_world[a];
  double r_along[3], r_across[3];
  const double* p_along[1] = {along};
  const double* p_across[1] = {across};
  ASSERT_TRUE(cost.Evaluate(p_along, r_along, nullptr));
  ASSERT_TRUE(cost.Evaluate(p_across, r_across, nullptr));
  EXPECT_LT(Eigen::Map<Eigen::Vector3d>(r_along).norm(), 0.5 * Eigen::Map<Eigen::Vector3d>(r_across).norm());
}

TEST(ShapePriorCost, ResidualAndJacobian) {
  const Eigen::VectorXd sigmas = Eigen::Vector3d(2.0, 1.0, 0.5);
  ShapePriorCost cost(sigmas, 4.0);
  double z[3] = {1.0, -1.0, 0.25};
  double r[3];
  const double* params[1] = {z};
  ASSERT_TRUE(cost.Evaluate(params, r, nullptr));
  EXPECT_NEAR(r[0], 1.0, 1e-15);
  EXPECT_NEAR(r[1], -2.0, 1e-15);
  EXPECT_NEAR(r[2], 1.0, 1e-15);
  ExpectJacobiansMatch(cost, {z}, 1e-7, "shape prior");
}

TEST(DetectionSizeCost, ResidualAndJacobian) {
  const Eigen::VectorXd z0 = Eigen::Vector3d(0.5, -0.2, 0.1);
  Eigen::Matrix<double, 3, Eigen::Dynamic> jacobian(3, 3);
  jacobian << 0.1, 0.0, -0.2, 0.05, 0.3, 0.0, 0.0, -0.1, 0.4;
  const Eigen::Vector3d size0(4.0, 1.5, 1.7), detected(4.3, 1.4, 1.8);
  DetectionSizeCost cost(z0, size0, jacobian, detected, 0.3, 0.25);
  double z[3] = {1.0, -1.0, 0.25};
  double r[3];
  const double* params[1] = {z};
  ASSERT_TRUE(cost.Evaluate(params, r, nullptr));
  const Eigen::Vector3d expected =
      std::sqrt(0.25) / 0.3 * (size0 + jacobian * (Eigen::Map<Eigen::Vector3d>(z) - z0) - detected);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(r[i], expected[i], 1e-14);
  ExpectJacobiansMatch(cost, {z}, 1e-7, "detection size");
}

TEST(ShapeLookup, LinearisedInsideBoxSizePredictsTheBox) {
  // The linearisation about a code predicts the inside box a quarter sigma
  // away better than the box at the code itself does.
  const ShapeLookup& lookup = Lookup();
  const int nr = lookup.num_components();
  Eigen::VectorXd z = Eigen::VectorXd::Zero(nr);
  z[0] = 0.5 * lookup.sigmas()[0];
  ShapeLookup::BoxSizeLinearisation lin;
  ASSERT_TRUE(lookup.LineariseInsideBoxSize(z, 0.5, &lin));
  EXPECT_LT((lin.size - lookup.InsideBox(z).Size()).norm(), 1e-12);
  ASSERT_EQ(lin.jacobian.cols(), nr);
  EXPECT_GT(lin.jacobian.cwiseAbs().maxCoeff(), 0.0);
  for (int i = 0; i < nr; ++i) {
    Eigen::VectorXd dz = Eigen::VectorXd::Zero(nr);
    dz[i] = 0.25 * lookup.sigmas()[i];
    const Eigen::Vector3d actual = lookup.InsideBox(z + dz).Size();
    const Eigen::Vector3d predicted = lin.size + lin.jacobian * dz;
    EXPECT_LE((predicted - actual).cwiseAbs().maxCoeff(),
              std::max(0.02, 0.5 * (lin.size - actual).cwiseAbs().maxCoeff()))
        << "component " << i << ": predicted " << predicted.transpose() << ", actual " << actual.transpose();
  }
  EXPECT_THROW(lookup.LineariseInsideBoxSize(Eigen::VectorXd::Zero(nr + 1), 0.5, &lin), Error);
}

}  // namespace
}  // namespace samp
