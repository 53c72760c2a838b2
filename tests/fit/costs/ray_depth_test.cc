// The ray-depth data term (ray_depth.h): residuals against a brute-force
// ray march, analytic Jacobians against central differences.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "libsamp/core/error.h"
#include "libsamp/core/pose.h"
#include "libsamp/fit/costs/ray_depth.h"
#include "libsamp/fit/costs/shape_ray.h"
#include "tests/fit/cost_test_util.h"

namespace samp {
namespace {

using testing::ExpectJacobiansMatch;
const ShapeLookup& Lookup() { return testing::CostLookup(); }

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

TEST(RayDepthCost, ResidualsAndJacobians) {
  const ShapeLookup& lookup = Lookup();
  std::mt19937 rng(8);
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::VectorXd z_true = 0.5 * lookup.sigmas();
  const auto surface = testing::SampleSurface(lookup, z_true, 80, &rng);
  const Eigen::Vector3d camera(1.0, -0.3, 2.0);
  // Huber and the mixture robustifier (mixture_loss), threshold 2 sigma each.
  for (const bool mixture : {false, true})
  for (const double yaw : {0.4, kPi - 1e-6, -2.0}) {
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
    DataCostOptions options;
    options.huber_threshold = 2.0;
    options.weight = 0.25;
    options.term = DataTerm::kRayDepth;
    options.camera_in_world = camera;
    options.mixture_loss = mixture;
    options.outlier_threshold = 2.0;
    RayDepthCost cost(&lookup, points, sigmas, options);
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
                              (mixture ? MixturePsi(scaled, options.outlier_threshold, nullptr)
                                       : HuberPsi(scaled, options.huber_threshold, nullptr));
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
  DataCostOptions bad;
  bad.term = DataTerm::kRayDepth;
  bad.camera_in_world = Eigen::Vector3d(4.0, 1.6, 15.0);
  EXPECT_THROW(RayDepthCost(&lookup, {Eigen::Vector3d(4.0, 1.6, 15.0)}, {0.1}, bad), Error);
}

// The batched marches (RayDistances, FirstCrossings: rays in lockstep slots,
// samples two at a time) return each ray's single-ray result bit for bit:
// rays from inside and outside the shape, towards it and away from it, from
// outside the grid box, batches of every size up to kRayBatch.
TEST(ShapeRay, BatchedMarchesEqualTheSingleRayOnesBitForBit) {
  const ShapeLookup& lookup = Lookup();
  const Eigen::VectorXd z = 0.5 * lookup.sigmas();
  const double* phi_z = lookup.DenseCached(z.data());
  std::mt19937 rng(21);
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Vector3d lo = lookup.grid().MinCorner(), hi = lookup.grid().MaxCorner();
  const Eigen::Vector3d centre = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  const auto surface = testing::SampleSurface(lookup, z, 200, &rng);
  auto same = [](double a, double b) { return std::memcmp(&a, &b, sizeof(a)) == 0; };
  // The crossing's cell as the Jacobian rows take it: LocateInside's at c.
  auto same_cell = [&](const double* c, const ShapeLookup::DenseCell& cell, bool in_cell) {
    ShapeLookup::DenseCell reference;
    if (lookup.LocateInside(c, &reference) != in_cell) return false;
    return !in_cell || (reference.base == cell.base && same(reference.f[0], cell.f[0]) &&
                        same(reference.f[1], cell.f[1]) && same(reference.f[2], cell.f[2]));
  };
  int found = 0, hits = 0;
  for (int trial = 0; trial < kRayBatch + 8; ++trial) {
    const int count = 1 + trial % kRayBatch;
    RayDistanceQuery near[kRayBatch];
    FirstCrossingQuery far[kRayBatch];
    const Eigen::Vector3d camera = centre + Eigen::Vector3d(3.0 * n(rng), 0.5 * n(rng), 3.0 * n(rng)) +
                                   Eigen::Vector3d(0.0, 0.0, 4.0);
    for (int r = 0; r < count; ++r) {
      // Points near the surface, off it along the ray (most), and points in
      // and around the grid box (some outside it).
      Eigen::Vector3d o;
      if (r % 4 != 3) {
        const Eigen::Vector3d& p = surface[size_t(trial * kRayBatch + r) % surface.size()];
        o = p + 0.1 * n(rng) * (p - camera).normalized();
      } else {
        for (int a = 0; a < 3; ++a) o[a] = centre[a] + 1.2 * half[a] * std::tanh(n(rng));
      }
      const Eigen::Vector3d u = (o - camera).normalized();
      for (int a = 0; a < 3; ++a) {
        near[r].o[a] = o[a];
        near[r].u[a] = far[r].u[a] = u[a];
      }
      near[r].phi_o = lookup.EvaluateDense(phi_z, near[r].o, nullptr, nullptr);
      far[r].max_lambda = r % 3 == 0 ? std::numeric_limits<double>::infinity() : (o - camera).norm();
    }
    RayDistances(lookup, phi_z, near, count);
    FirstCrossings(lookup, phi_z, camera.data(), far, count);
    for (int r = 0; r < count; ++r) {
      double distance = 0.0, c[3], g_c[3];
      const bool near_found = RayDistance(lookup, phi_z, near[r].o, near[r].phi_o, near[r].u, &distance, c, g_c);
      ASSERT_EQ(near[r].found, near_found) << trial << " " << r;
      if (near_found) {
        ++found;
        EXPECT_TRUE(same(near[r].distance, distance)) << trial << " " << r;
        EXPECT_TRUE(same_cell(near[r].c, near[r].cell, near[r].in_cell)) << trial << " " << r;
        for (int a = 0; a < 3; ++a) {
          EXPECT_TRUE(same(near[r].c[a], c[a]) && same(near[r].g_c[a], g_c[a])) << trial << " " << r;
        }
      }
      double lambda = 0.0, phi_min = 0.0;
      const bool far_hit = FirstCrossing(lookup, phi_z, camera.data(), far[r].u, &lambda, c, g_c, &phi_min,
                                         /*refine_miss=*/false, far[r].max_lambda);
      ASSERT_EQ(far[r].hit, far_hit) << trial << " " << r;
      if (far_hit) {
        ++hits;
        EXPECT_TRUE(same(far[r].lambda, lambda)) << trial << " " << r;
        EXPECT_TRUE(same_cell(far[r].c, far[r].cell, far[r].in_cell)) << trial << " " << r;
        for (int a = 0; a < 3; ++a) {
          EXPECT_TRUE(same(far[r].c[a], c[a]) && same(far[r].g_c[a], g_c[a])) << trial << " " << r;
        }
      }
    }
  }
  EXPECT_GT(found, 50);
  EXPECT_GT(hits, 50);
}

}  // namespace
}  // namespace samp
