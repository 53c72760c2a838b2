// Test helpers of the fit layer: a small shape model built in memory from
// analytic rounded-box SDFs with PCA, and points sampled on a shape's zero
// level set. Deterministic (seeded); shared by the fit tests and fit_bench.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "libsamp/core/grid_spec.h"
#include "libsamp/fit/motion_model.h"
#include "libsamp/model/shape_lookup.h"
#include "libsamp/data/track.h"
#include "libsamp/model/shape_model.h"

namespace samp::testing {

// Three draws of `draw` in the order z, y, x, returned as (x, y, z). C++
// leaves the evaluation order of a call's arguments (and of an operator's
// operands) unspecified: Eigen::Vector3d(n(rng), n(rng), n(rng)) drew z first
// under GCC and x first under clang, so the tests' random data differed by
// compiler and three tests tuned on GCC's data failed under clang. The tests
// now draw in GCC's former order, spelled out, so their data stays as it was.
template <typename Draw, typename Rng>
Eigen::Vector3d DrawVector(Draw& draw, Rng& rng) {
  const double z = draw(rng);
  const double y = draw(rng);
  const double x = draw(rng);
  return Eigen::Vector3d(x, y, z);
}

// Signed distance to a box of half extents b centred at c, corners rounded by r.
inline double RoundBoxSdf(const Eigen::Vector3d& p, const Eigen::Vector3d& c,
                          const Eigen::Vector3d& b, double r) {
  const Eigen::Vector3d q = (p - c).cwiseAbs() - b + Eigen::Vector3d::Constant(r);
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0) - r;
}

// A car-like body (lower box) with a cabin (upper box), bottom at y = 0
// (object frame: x front, y down, z left).
inline double CarSdf(const Eigen::Vector3d& p, double length, double width, double body_height,
                     double cabin_height, double cabin_length) {
  const double body = RoundBoxSdf(p, Eigen::Vector3d(0, -0.2 - body_height / 2, 0),
                                  Eigen::Vector3d(length / 2, body_height / 2, width / 2), 0.15);
  const double cabin =
      RoundBoxSdf(p, Eigen::Vector3d(-0.1 * length, -0.2 - body_height - cabin_height / 2 + 0.1, 0),
                  Eigen::Vector3d(cabin_length / 2, cabin_height / 2, width / 2 - 0.1), 0.15);
  // Wheels region: fill down to the ground with a slightly narrower box.
  const double under = RoundBoxSdf(p, Eigen::Vector3d(0, -0.2, 0),
                                   Eigen::Vector3d(length / 2 - 0.3, 0.2, width / 2 - 0.05), 0.05);
  return std::min(std::min(body, cabin), under);
}

// PCA model with `num_components` components from `num_shapes` random cars on
// a grid with `voxel_size` (default car grid box).
inline ShapeModel MakeSyntheticModel(int num_components = 5, double voxel_size = 0.1,
                                     int num_shapes = 16, unsigned seed = 7) {
  ShapeModel model;
  model.grid = GridSpec::FromBox(Eigen::Vector3d(-3.0, -2.3, -1.4),
                                 Eigen::Vector3d(3.0, 0.5, 1.4), voxel_size);
  const GridSpec& g = model.grid;
  const int64_t d = g.NumVoxels();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd samples(d, num_shapes);
  for (int s = 0; s < num_shapes; ++s) {
    const double length = 3.6 + 1.0 * u(rng), width = 1.55 + 0.3 * u(rng);
    const double body = 0.5 + 0.3 * u(rng), cabin = 0.4 + 0.3 * u(rng);
    const double cabin_length = 1.6 + 0.8 * u(rng);
    for (int k = 0; k < g.dims.z(); ++k)
      for (int j = 0; j < g.dims.y(); ++j)
        for (int i = 0; i < g.dims.x(); ++i)
          samples(g.Index(i, j, k), s) =
              CarSdf(g.Position(i, j, k), length, width, body, cabin, cabin_length);
  }
  const Eigen::VectorXd mean = samples.rowwise().mean();
  samples.colwise() -= mean;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(samples.transpose() * samples);
  model.mean = mean.cast<float>();
  model.components.resize(d, num_components);
  model.eigenvalues.resize(num_components);
  for (int r = 0; r < num_components; ++r) {
    const int col = num_shapes - 1 - r;  // decreasing eigenvalues
    const double lambda = eig.eigenvalues()[col];
    const Eigen::VectorXd v = samples * eig.eigenvectors().col(col) / std::sqrt(lambda);
    model.components.col(r) = v.cast<float>();
    model.eigenvalues[r] = lambda / (num_shapes - 1);
  }
  return model;
}

// Points on the zero level set of phi_z (object frame): random points in the
// shape's box projected by Newton steps along the gradient; keeps those that
// converge (|phi| < 1e-3). Only points visible from direction `view` (unit,
// object frame, pointing from the surface towards the camera) when non-zero.
inline std::vector<Eigen::Vector3d> SampleSurface(const ShapeLookup& lookup,
                                                  const Eigen::VectorXd& z, int count,
                                                  std::mt19937* rng,
                                                  const Eigen::Vector3d& view = Eigen::Vector3d::Zero()) {
  std::uniform_real_distribution<double> ux(-2.6, 2.6), uy(-1.9, 0.1), uz(-1.1, 1.1);
  std::vector<Eigen::Vector3d> out;
  int attempts = 0;
  while (int(out.size()) < count && attempts < 100 * count) {
    ++attempts;
    const double pz = uz(*rng), py = uy(*rng), px = ux(*rng);  // GCC's former order (DrawVector)
    Eigen::Vector3d p(px, py, pz);
    Eigen::Vector3d grad;
    double phi = 1.0;
    for (int it = 0; it < 20; ++it) {
      phi = lookup.Evaluate(z, p, &grad);
      if (std::abs(phi) < 1e-4) break;
      const double g2 = grad.squaredNorm();
      if (g2 < 1e-8) break;
      p -= phi * grad / g2;
    }
    if (std::abs(phi) >= 1e-3) continue;
    if (view.squaredNorm() > 0 && grad.dot(view) <= 0.0) continue;
    out.push_back(p);
  }
  return out;
}

// Keeps the points (world) that the camera at `camera_in_world` sees: no
// part of phi_z (placed by world_from_object) lies on the ray in front of
// them (steps of 1 cm up to 3 m in front, 2 cm tolerance). Stereo sees only
// the visible surface; points sampled on self-occluded parts would lie
// behind it.
inline void KeepVisible(const ShapeLookup& lookup, const Eigen::VectorXd& z, const Eigen::Isometry3d& world_from_object,
                        const Eigen::Vector3d& camera_in_world, std::vector<Eigen::Vector3d>* points,
                        std::vector<double>* sigmas) {
  const Eigen::Isometry3d object_from_world = world_from_object.inverse();
  size_t kept = 0;
  for (size_t i = 0; i < points->size(); ++i) {
    const Eigen::Vector3d p = (*points)[i];
    const Eigen::Vector3d u = (p - camera_in_world).normalized();
    bool visible = true;
    for (double d = 0.02; d < 3.0 && visible; d += 0.01) {
      visible = lookup.Evaluate(z, Eigen::Vector3d(object_from_world * Eigen::Vector3d(p - d * u))) >= 0.0;
    }
    if (!visible) continue;
    (*points)[kept] = p;
    (*sigmas)[kept] = (*sigmas)[i];
    ++kept;
  }
  points->resize(kept);
  sigmas->resize(kept);
}

struct Synthetic {
  Track track;
  Eigen::VectorXd z_true;
  std::vector<Eigen::Vector4d> poses_true;
  std::vector<Eigen::Vector2d> velocities_true;
};

// A synthetic track of `num_frames` frames at 10 Hz seen from a static camera at the
// world origin (world = camera), road plane y = 1.65.
// `z_true` (R values; default (1.2, -0.8, 0.6, 0, -0.5) sigma) and the first
// pose `start` (tx, ty, tz, theta; default (-4, 1.65, 14, 0.4)) may be given.
inline Synthetic MakeTrack(const ShapeLookup& lookup, int num_frames, double speed, double yaw_rate,
                    int points_per_frame, unsigned seed, int flipped_frame = -1,
                    const Eigen::VectorXd* z_true = nullptr, const Eigen::Vector4d* start = nullptr) {
  Synthetic s;
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  s.z_true = Eigen::VectorXd(5);
  s.z_true << 1.2, -0.8, 0.6, 0.0, -0.5;
  s.z_true = s.z_true.cwiseProduct(lookup.sigmas());
  if (z_true != nullptr) s.z_true = *z_true;
  const Eigen::Vector3d true_size = lookup.InsideBox(s.z_true).Size();
  s.track.id = 3;
  s.track.sequence = "synthetic";
  Eigen::Vector4d pose(-4.0, 1.65, 14.0, 0.4);
  if (start != nullptr) pose = *start;
  Eigen::Vector2d vel(speed, yaw_rate);
  const MotionModel model = SelectMotionModel(speed, yaw_rate, 1e-9, 1e-9);
  for (int k = 0; k < num_frames; ++k) {
    if (k > 0) {
      double next[6];
      PredictMotion(model == MotionModel::kStanding ? MotionModel::kStraight : model, pose.data(),
                    vel.data(), 0.1, next, nullptr, nullptr);
      pose << next[0], next[1], next[2], WrapAngle(next[3]);
    }
    s.poses_true.push_back(pose);
    s.velocities_true.push_back(vel);
    TrackFrame f;
    f.frame = k;
    f.time = 0.1 * k;
    f.ground_plane_in_world = Eigen::Vector4d(0, -1, 0, 1.65);
    const Eigen::Isometry3d world_from_object = WorldFromObject(pose.head<3>(), pose[3]);
    // Detection: noisy bottom centre and yaw (camera = world here).
    const Eigen::Vector3d detection_noise = DrawVector(n, rng);
    f.detection.position = pose.head<3>() + Eigen::Vector3d(0.1 * detection_noise.x(), 0.05 * detection_noise.y(),
                                                            0.1 * detection_noise.z());
    f.detection.rotation_y = WrapAngle(pose[3] + 0.05 * n(rng) + (k == flipped_frame ? M_PI : 0.0));
    // Size: the true shape's box (a detector without size error).
    f.detection.length = true_size.x();
    f.detection.height = true_size.y();
    f.detection.width = true_size.z();
    // Points visible from the camera, with noise, plus 5 % outliers.
    const Eigen::Vector3d view =
        (world_from_object.inverse() * Eigen::Vector3d::Zero()).normalized();
    const auto surface = testing::SampleSurface(lookup, s.z_true, points_per_frame, &rng, view);
    for (const auto& p : surface) {
      const Eigen::Vector3d w = world_from_object * p;
      f.candidate_points_in_world.push_back(w + 0.03 * DrawVector(n, rng));
      f.candidate_sigmas.push_back(0.05);
    }
    for (int i = 0; i < points_per_frame / 20; ++i) {
      const Eigen::Vector3d clutter = DrawVector(n, rng);
      f.candidate_points_in_world.push_back(
          pose.head<3>() + Eigen::Vector3d(2.0 * clutter.x(), -0.7 + 0.5 * clutter.y(), 2.0 * clutter.z()));
      f.candidate_sigmas.push_back(0.05);
    }
    s.track.frames.push_back(f);
  }
  return s;
}

}  // namespace samp::testing
