#include "libsamp/model/shape_model.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include "libsamp/core/error.h"
#include "libsamp/model/shape_lookup.h"
#include "libsamp/sdf/vdb_io.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() /
            ("samp_model_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter_++));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string File(const std::string& name) const { return (path_ / name).string(); }

 private:
  static inline int counter_ = 0;
  fs::path path_;
};

ShapeModel RandomModel(int num_components, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  ShapeModel model;
  model.grid.origin = Eigen::Vector3d(-0.31, -0.22, -0.27);
  model.grid.voxel_size = 0.1;
  model.grid.dims = Eigen::Vector3i(7, 6, 5);
  const int64_t dim = model.grid.NumVoxels();
  model.mean.resize(dim);
  for (int64_t i = 0; i < dim; ++i) model.mean[i] = uniform(rng);
  model.components.resize(dim, num_components);
  for (int64_t i = 0; i < model.components.size(); ++i) model.components.data()[i] = uniform(rng);
  model.eigenvalues.resize(num_components);
  for (int r = 0; r < num_components; ++r) model.eigenvalues[r] = 1.0 / (r + 1);
  model.total_variance = 3.5;
  model.training_shapes = {"sedan", "van", "hatch back"};
  model.options_json = R"({"pca":{"num_components":3},"voxel":0.1})";
  return model;
}

// Independent reference: trilinear interpolation of a dense grid by brute
// force (the 8 weights from the fractional voxel coordinates), with the
// documented continuation outside the box.
double BruteForce(const GridSpec& grid, const Eigen::VectorXf& shape, const Eigen::Vector3d& p) {
  const Eigen::Vector3d lo = grid.MinCorner(), hi = grid.MaxCorner();
  const Eigen::Vector3d q = p.cwiseMax(lo).cwiseMin(hi);
  const Eigen::Vector3d x = grid.ToVoxel(q);
  double value = 0.0;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const double w = std::max(0.0, 1.0 - std::abs(x.x() - i)) *
                         std::max(0.0, 1.0 - std::abs(x.y() - j)) *
                         std::max(0.0, 1.0 - std::abs(x.z() - k));
        value += w * shape[grid.Index(i, j, k)];
      }
  return value + (p - q).norm();
}

// The bits of a double, for comparisons bit for bit (NaN included).
uint64_t Bits(double v) {
  uint64_t b;
  std::memcpy(&b, &v, sizeof(b));
  return b;
}

// The code of the lane tests (RandomModel(5, 11)): a shape with inside and outside in the grid.
Eigen::VectorXd LaneTestCode() {
  Eigen::VectorXd code(5);
  code << 0.3, -0.8, 1.1, 0.25, -1.7;
  return code;
}

// Random points within `margin` metres around the grid box, away from cell
// faces (where the trilinear gradient jumps) and from the box faces.
std::vector<Eigen::Vector3d> RandomPoints(const GridSpec& grid, double margin, int n,
                                          unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<Eigen::Vector3d> points;
  const Eigen::Vector3d lo = grid.MinCorner().array() - margin;
  const Eigen::Vector3d hi = grid.MaxCorner().array() + margin;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  while (int(points.size()) < n) {
    Eigen::Vector3d p;
    for (int a = 0; a < 3; ++a) p[a] = lo[a] + (hi[a] - lo[a]) * unit(rng);
    const Eigen::Vector3d x = grid.ToVoxel(p);
    bool near_face = false;
    for (int a = 0; a < 3; ++a) near_face |= std::abs(x[a] - std::round(x[a])) < 1e-3;
    if (!near_face) points.push_back(p);
  }
  return points;
}

TEST(ShapeLookup, EvaluateMatchesBruteForceTrilinear) {
  const ShapeModel model = RandomModel(3, 1);
  const ShapeLookup lookup(model);
  const Eigen::VectorXd z = Eigen::Vector3d(0.7, -1.3, 0.4);
  const Eigen::VectorXf shape = model.Shape(z);
  ASSERT_EQ(shape.size(), model.NumVoxels());
  const double* dense = lookup.DenseCached(z.data());
  for (const auto& p : RandomPoints(model.grid, 0.4, 400, 2)) {
    EXPECT_NEAR(lookup.Evaluate(z, p), BruteForce(model.grid, shape, p), 1e-5) << p.transpose();
    EXPECT_NEAR(lookup.EvaluateDense(dense, p.data(), nullptr, nullptr), lookup.Evaluate(z, p), 1e-12);
  }
  // At the samples the lookup returns the sample.
  for (int k : {0, 2, 4})
    for (int j : {0, 5})
      for (int i : {0, 3, 6}) {
        EXPECT_NEAR(lookup.Evaluate(z, model.grid.Position(i, j, k)),
                    shape[model.grid.Index(i, j, k)], 1e-5);
      }
  // The dense grids agree with the model's.
  const std::vector<float> dense_float = lookup.Dense(z);
  ASSERT_EQ(int64_t(dense_float.size()), model.NumVoxels());
  for (int64_t v = 0; v < model.NumVoxels(); ++v) {
    EXPECT_NEAR(dense_float[size_t(v)], shape[v], 1e-5);
    EXPECT_NEAR(dense[v], shape[v], 1e-5);
  }
}

// The dense grids hold mu_v + sum_r W_vr z_r summed in that order (as
// Evaluate sums a corner), bit for bit, for R = 5 (its two-voxel kernel) on an
// even and an odd number of voxels.
TEST(ShapeLookup, DenseGridsSumEachVoxelInOrder) {
  ShapeModel odd = RandomModel(5, 3);
  odd.grid.dims = Eigen::Vector3i(7, 5, 3);
  odd.mean.conservativeResize(odd.grid.NumVoxels());
  odd.components.conservativeResize(odd.grid.NumVoxels(), 5);
  for (const ShapeModel& model : {RandomModel(5, 3), odd}) {
    const ShapeLookup lookup(model);
    Eigen::VectorXd z(5);
    z << 0.7, -1.3, 0.4, 2.1, -0.05;
    const double* dense = lookup.DenseCached(z.data());
    const std::vector<float> dense_float = lookup.Dense(z);
    for (int64_t v = 0; v < model.NumVoxels(); ++v) {
      double s = model.mean[v];
      for (int r = 0; r < 5; ++r) s += double(model.components(v, r)) * z[r];
      EXPECT_EQ(dense[v], s) << v;
      EXPECT_EQ(dense_float[size_t(v)], float(s)) << v;
    }
  }
}

// DenseValuePair (two points in SSE2 lanes) returns EvaluateDenseValue's bits
// at each point: inside the grid box, on its faces and corners, at a sample,
// outside it (also just outside) and at non-finite points, in either lane;
// with both points inside, EvaluateInside returns LocateInside's cells and
// DenseAt's values and gradients bit for bit (with SSE2).
TEST(ShapeLookup, DenseValuePairEqualsOneAtATimeBitForBit) {
  const ShapeModel model = RandomModel(5, 11);
  const ShapeLookup lookup(model);
  const Eigen::VectorXd code = LaneTestCode();
  const double* dense = lookup.DenseCached(code.data());
  std::vector<Eigen::Vector3d> points = RandomPoints(model.grid, 0.02, 300, 5);
  for (const Eigen::Vector3d& p : RandomPoints(model.grid, 0.5, 100, 6)) points.push_back(p);
  const Eigen::Vector3d lo = model.grid.MinCorner(), hi = model.grid.MaxCorner();
  points.push_back(lo);
  points.push_back(hi);
  points.push_back(Eigen::Vector3d(hi.x(), lo.y(), hi.z()));
  points.push_back(model.grid.Position(3, 2, 1));  // a sample: fractions 0
  points.push_back(Eigen::Vector3d(std::nextafter(hi.x(), 1e9), 0.0, 0.0));
  points.push_back(Eigen::Vector3d(std::nextafter(lo.x(), -1e9), 0.0, 0.0));
  points.push_back(Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0));
  points.push_back(Eigen::Vector3d(0.0, std::numeric_limits<double>::infinity(), 0.0));
  const ShapeLookup::DenseValuePair pair(lookup, dense);
  int both_inside = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    for (size_t j : {i, (i + 1) % points.size(), (i + 7) % points.size()}) {
      const double x[2] = {points[i].x(), points[j].x()}, y[2] = {points[i].y(), points[j].y()};
      const double z[2] = {points[i].z(), points[j].z()};
      double values[2];
      pair.Evaluate(x, y, z, values);
      EXPECT_EQ(Bits(values[0]), Bits(lookup.EvaluateDenseValue(dense, points[i].data()))) << i << " " << j;
      EXPECT_EQ(Bits(values[1]), Bits(lookup.EvaluateDenseValue(dense, points[j].data()))) << i << " " << j;
      // EvaluateInside: the cells, values and gradients of LocateInside and
      // DenseAt when both points lie inside the box, else false.
      ShapeLookup::DenseCell cells[2], cell_i, cell_j;
      double g[2][3];
      const bool inside =
          lookup.LocateInside(points[i].data(), &cell_i) && lookup.LocateInside(points[j].data(), &cell_j);
      both_inside += inside;
      const bool lanes = pair.EvaluateInside(x, y, z, cells, values, g);
#ifdef __SSE2__
      ASSERT_EQ(lanes, inside) << i << " " << j;
#else
      ASSERT_FALSE(lanes);  // the scalar path is the caller's
#endif
      if (!lanes) continue;
      ShapeLookup::DenseCell value_cells[2];
      double value_only[2];
      ASSERT_TRUE(pair.EvaluateInside(x, y, z, value_cells, value_only, nullptr));  // the values only
      for (int k = 0; k < 2; ++k) {
        EXPECT_EQ(value_cells[k].base, cells[k].base);
        EXPECT_EQ(Bits(value_only[k]), Bits(values[k]));
      }
      for (int k = 0; k < 2; ++k) {
        const ShapeLookup::DenseCell& cell = k == 0 ? cell_i : cell_j;
        double g_ref[3];
        const double value = lookup.DenseAt(dense, cell, g_ref);
        EXPECT_EQ(cells[k].base, cell.base);
        EXPECT_EQ(Bits(values[k]), Bits(value)) << i << " " << j;
        for (int a = 0; a < 3; ++a) {
          EXPECT_EQ(Bits(cells[k].f[a]), Bits(cell.f[a])) << i << " " << j;
          EXPECT_EQ(Bits(g[k][a]), Bits(g_ref[a])) << i << " " << j;
        }
      }
    }
  }
  EXPECT_GT(both_inside, 300);
  // Evaluate4 and EvaluateInside4 (where the CPU has AVX): each of the four
  // lanes is the one-point lookup's, whatever the other lanes hold.
  if (!ShapeLookup::DenseValuePair::HasEvaluate4()) GTEST_SKIP() << "no AVX: Evaluate4 is not used";
  int four_inside = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const size_t lanes[4] = {i, (i + 1) % points.size(), (i + 7) % points.size(), (i + 101) % points.size()};
    double x[4], y[4], z[4], values[4];
    for (int k = 0; k < 4; ++k) {
      x[k] = points[lanes[k]].x();
      y[k] = points[lanes[k]].y();
      z[k] = points[lanes[k]].z();
    }
    pair.Evaluate4(x, y, z, values);
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(Bits(values[k]), Bits(lookup.EvaluateDenseValue(dense, points[lanes[k]].data()))) << i << " " << k;
    }
    // EvaluateInside4: LocateInside's cells and DenseAt's values and
    // gradients when all four lie inside the box, else false.
    ShapeLookup::DenseCell cells[4], reference_cells[4];
    double g[4][3];
    bool all_inside = true;
    for (int k = 0; k < 4; ++k) {
      all_inside = lookup.LocateInside(points[lanes[k]].data(), &reference_cells[k]) && all_inside;
    }
    ASSERT_EQ(pair.EvaluateInside4(x, y, z, cells, values, g), all_inside) << i;
    if (!all_inside) continue;
    ++four_inside;
    for (int k = 0; k < 4; ++k) {
      double g_ref[3];
      const double value = lookup.DenseAt(dense, reference_cells[k], g_ref);
      EXPECT_EQ(cells[k].base, reference_cells[k].base) << i << " " << k;
      EXPECT_EQ(Bits(values[k]), Bits(value)) << i << " " << k;
      for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(Bits(cells[k].f[a]), Bits(reference_cells[k].f[a])) << i << " " << k;
        EXPECT_EQ(Bits(g[k][a]), Bits(g_ref[a])) << i << " " << k;
      }
    }
  }
  EXPECT_GT(four_inside, 40);
}

TEST(ShapeLookup, EvaluateCellsEqualsEvaluateDenseBitForBit) {
  // Every count and offset over points inside, on and outside the grid box
  // (and not finite): the lanes' groups mixed with the one-point path.
  const ShapeModel model = RandomModel(5, 11);
  const ShapeLookup lookup(model);
  const Eigen::VectorXd code = LaneTestCode();
  const double* dense = lookup.DenseCached(code.data());
  std::vector<Eigen::Vector3d> points = RandomPoints(model.grid, 0.02, 40, 7);
  for (const Eigen::Vector3d& p : RandomPoints(model.grid, 0.5, 12, 8)) points.insert(points.begin() + 9, p);
  points.insert(points.begin() + 3, Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0));
  points.push_back(model.grid.MaxCorner());
  std::vector<double> x, y, z;
  for (const Eigen::Vector3d& p : points) x.push_back(p.x()), y.push_back(p.y()), z.push_back(p.z());
  const ShapeLookup::DenseValuePair pair(lookup, dense);
  int inside = 0, outside = 0;
  constexpr int kMax = 64;
  ASSERT_LT(points.size(), size_t(kMax));
  for (int first = 0; first < 4; ++first) {
    for (int n = 0; first + n <= int(points.size()); ++n) {
      ShapeLookup::DenseCell cells[kMax];
      bool in_cell[kMax], in_cell_values[kMax];
      double values[kMax + 1], value_only[kMax], g[kMax][3];
      values[n] = -7.0;
      pair.EvaluateCells(n, &x[first], &y[first], &z[first], cells, in_cell, values, g);
      EXPECT_EQ(values[n], -7.0) << "wrote past the points";
      pair.EvaluateCells(n, &x[first], &y[first], &z[first], cells, in_cell_values, value_only, nullptr);
      for (int k = 0; k < n; ++k) {
        const double* p = points[size_t(first + k)].data();
        ShapeLookup::DenseCell cell;
        const bool expected_in_cell = lookup.LocateInside(p, &cell);
        double g_ref[3];
        const double value = lookup.EvaluateDense(dense, p, g_ref, nullptr);
        ASSERT_EQ(in_cell[k], expected_in_cell) << first << " " << n << " " << k;
        EXPECT_EQ(in_cell_values[k], in_cell[k]);
        EXPECT_EQ(Bits(values[k]), Bits(value)) << first << " " << n << " " << k;
        EXPECT_EQ(Bits(value_only[k]), Bits(value)) << first << " " << n << " " << k;
        if (!std::isfinite(value)) continue;
        for (int a = 0; a < 3; ++a) EXPECT_EQ(Bits(g[k][a]), Bits(g_ref[a])) << k << " " << a;
        if (!expected_in_cell) {
          ++outside;
          continue;
        }
        ++inside;
        EXPECT_EQ(cells[k].base, cell.base);
        for (int a = 0; a < 3; ++a) EXPECT_EQ(Bits(cells[k].f[a]), Bits(cell.f[a]));
      }
    }
  }
  EXPECT_GT(inside, 1000);
  EXPECT_GT(outside, 100);
}

// Reference for InsideBox: every inside voxel and its crossings towards
// outside neighbours along each axis (linear interpolation), all voxels scanned.
AlignedBox InsideBoxByFullScan(const ShapeLookup& lookup, const Eigen::VectorXd& z) {
  const std::vector<float> phi = lookup.Dense(z);
  const GridSpec& grid = lookup.grid();
  const Eigen::Vector3i& n = grid.dims;
  AlignedBox box;
  for (int k = 0; k < n.z(); ++k)
    for (int j = 0; j < n.y(); ++j)
      for (int i = 0; i < n.x(); ++i) {
        const float v = phi[size_t(grid.Index(i, j, k))];
        if (!(v < 0.0f)) continue;
        const Eigen::Vector3d p = grid.Position(i, j, k);
        box.Extend(p);
        const int idx[3] = {i, j, k};
        for (int a = 0; a < 3; ++a)
          for (int s = -1; s <= 1; s += 2) {
            int nb[3] = {i, j, k};
            nb[a] = idx[a] + s;
            if (nb[a] < 0 || nb[a] >= n[a]) continue;
            const float w = phi[size_t(grid.Index(nb[0], nb[1], nb[2]))];
            if (w < 0.0f) continue;
            Eigen::Vector3d e = p;
            e[a] += s * grid.voxel_size * double(v) / double(v - w);
            box.Extend(e);
          }
      }
  return box;
}

TEST(ShapeLookup, InsideBoxEqualsTheFullScan) {
  // Random fields (inside voxels on the grid's border too) with R = 3 and
  // R = 5 (the compile-time kernel), and a ball (inside voxels in the middle).
  for (const int r : {3, 5}) {
    const ShapeModel model = RandomModel(r, 40 + r);
    const ShapeLookup lookup(model);
    std::mt19937 rng(7);
    std::normal_distribution<double> n(0.0, 1.0);
    for (int trial = 0; trial < 20; ++trial) {
      Eigen::VectorXd z(r);
      for (int c = 0; c < r; ++c) z[c] = 0.8 * n(rng);
      const AlignedBox fast = lookup.InsideBox(z), full = InsideBoxByFullScan(lookup, z);
      ASSERT_EQ(fast.IsEmpty(), full.IsEmpty());
      if (full.IsEmpty()) continue;
      EXPECT_EQ(fast.min, full.min) << "R " << r << " trial " << trial;
      EXPECT_EQ(fast.max, full.max) << "R " << r << " trial " << trial;
    }
  }
  ShapeModel ball = RandomModel(5, 3);
  for (int k = 0; k < ball.grid.dims.z(); ++k)
    for (int j = 0; j < ball.grid.dims.y(); ++j)
      for (int i = 0; i < ball.grid.dims.x(); ++i) {
        const int64_t v = ball.grid.Index(i, j, k);
        ball.mean[v] = float(ball.grid.Position(i, j, k).norm() - 0.17);
        for (int c = 0; c < 5; ++c) ball.components(v, c) *= 0.02f;
      }
  const ShapeLookup lookup(ball);
  for (const double scale : {0.0, 1.0, -1.0}) {
    const Eigen::VectorXd z = Eigen::VectorXd::Constant(5, scale);
    const AlignedBox fast = lookup.InsideBox(z), full = InsideBoxByFullScan(lookup, z);
    ASSERT_FALSE(full.IsEmpty());
    EXPECT_EQ(fast.min, full.min);
    EXPECT_EQ(fast.max, full.max);
    EXPECT_GT(fast.min.x(), ball.grid.MinCorner().x() + 0.05);  // away from the border
  }
  // Nowhere inside: empty.
  ShapeModel empty = ball;
  for (int64_t v = 0; v < empty.NumVoxels(); ++v) empty.mean[v] = 1.0f;
  EXPECT_TRUE(ShapeLookup(empty).InsideBox(Eigen::VectorXd::Zero(5)).IsEmpty());
}

// The linearised box size from InsideBox at the code and at the steps, as
// LineariseInsideBoxSize documents it (the reference it must equal bit for bit).
bool LineariseByInsideBoxes(const ShapeLookup& lookup, const Eigen::VectorXd& z, double step,
                            ShapeLookup::BoxSizeLinearisation* out) {
  const AlignedBox box = lookup.InsideBox(z);
  if (box.IsEmpty()) return false;
  out->size = box.Size();
  out->jacobian.resize(3, lookup.num_components());
  for (int i = 0; i < lookup.num_components(); ++i) {
    const double h = step * lookup.sigmas()[i];
    Eigen::VectorXd plus = z, minus = z;
    plus[i] += h;
    minus[i] -= h;
    const AlignedBox a = lookup.InsideBox(plus), b = lookup.InsideBox(minus);
    if (a.IsEmpty() || b.IsEmpty()) return false;
    out->jacobian.col(i) = (a.Size() - b.Size()) / (2.0 * h);
  }
  return true;
}

TEST(ShapeLookup, LinearisedInsideBoxSizeEqualsTheBoxesAtTheSteps) {
  // Random fields (signs change everywhere, inside voxels on the border), a
  // ball (a thin band of voxels that can change sign) and steps from a
  // hundredth of a sigma to two sigmas.
  ShapeModel ball = RandomModel(5, 3);
  for (int k = 0; k < ball.grid.dims.z(); ++k)
    for (int j = 0; j < ball.grid.dims.y(); ++j)
      for (int i = 0; i < ball.grid.dims.x(); ++i) {
        const int64_t v = ball.grid.Index(i, j, k);
        ball.mean[v] = float(ball.grid.Position(i, j, k).norm() - 0.17);
        for (int c = 0; c < 5; ++c) ball.components(v, c) *= 0.02f;
      }
  const std::vector<ShapeModel> models = {RandomModel(3, 43), RandomModel(5, 45), ball};
  int compared = 0;
  for (const ShapeModel& model : models) {
    const ShapeLookup lookup(model);
    const int r = lookup.num_components();
    std::mt19937 rng(11);
    std::normal_distribution<double> n(0.0, 1.0);
    for (int trial = 0; trial < 12; ++trial) {
      Eigen::VectorXd z(r);
      for (int c = 0; c < r; ++c) z[c] = (trial == 0 ? 0.0 : 0.8) * n(rng);
      for (const double step : {0.01, 0.5, 2.0}) {
        ShapeLookup::BoxSizeLinearisation fast, reference;
        const bool ok = lookup.LineariseInsideBoxSize(z, step, &fast);
        ASSERT_EQ(ok, LineariseByInsideBoxes(lookup, z, step, &reference)) << "trial " << trial << " step " << step;
        if (!ok) continue;
        ++compared;
        EXPECT_EQ(fast.size, reference.size) << "trial " << trial << " step " << step;
        EXPECT_EQ(fast.jacobian, reference.jacobian) << "trial " << trial << " step " << step;
      }
    }
  }
  EXPECT_GT(compared, 60);
}

TEST(ShapeLookup, DenseCacheFollowsTheCodeAndTheLookup) {
  const ShapeModel model_a = RandomModel(3, 11), model_b = RandomModel(3, 12);
  const ShapeLookup a(model_a), b(model_b);
  const Eigen::VectorXd z1 = Eigen::Vector3d(0.5, 0.1, -0.2), z2 = Eigen::Vector3d(-0.4, 0.3, 0.9);
  const Eigen::Vector3d p(0.02, 0.07, -0.05);
  for (const auto& [lookup, z] : {std::make_pair(&a, z1), std::make_pair(&a, z2), std::make_pair(&b, z2),
                                  std::make_pair(&a, z2), std::make_pair(&b, z1)}) {
    const double* dense = lookup->DenseCached(z.data());
    EXPECT_NEAR(lookup->EvaluateDense(dense, p.data(), nullptr, nullptr), lookup->Evaluate(z, p), 1e-12);
  }
}

TEST(ShapeLookup, CellLookupEqualsEvaluateDenseBitForBit) {
  // R = 3 (the general kernel), 5 and 10 (compile-time kernels); random
  // points inside the box, points on cell and box faces and the box's
  // corners; points outside the box (and non-finite ones) have no cell.
  for (const int r : {3, 5, 10}) {
    const ShapeModel model = RandomModel(r, 40 + unsigned(r));
    const ShapeLookup lookup(model);
    Eigen::VectorXd z(r);
    for (int i = 0; i < r; ++i) z[i] = 0.3 * (i + 1) * (i % 2 ? -1.0 : 1.0);
    const double* dense = lookup.DenseCached(z.data());
    const GridSpec& grid = lookup.grid();
    std::vector<Eigen::Vector3d> points = RandomPoints(grid, 0.0, 300, 9);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) {
          points.push_back(grid.Position(i * (grid.dims.x() - 1) / 2, j * (grid.dims.y() - 1) / 2,
                                         k * (grid.dims.z() - 1) / 2));
        }
    points.push_back(grid.MaxCorner());
    points.push_back(grid.MinCorner());
    for (const Eigen::Vector3d& p : points) {
      ShapeLookup::DenseCell cell;
      ASSERT_TRUE(lookup.LocateInside(p.data(), &cell)) << p.transpose();
      double g_ref[3], g[3];
      std::vector<double> dz_ref(static_cast<size_t>(r)), dz(static_cast<size_t>(r));
      const double v_ref = lookup.EvaluateDense(dense, p.data(), g_ref, dz_ref.data());
      const double v = lookup.DenseAt(dense, cell, g);
      lookup.CodeGradientAt(cell, dz.data());
      EXPECT_EQ(std::memcmp(&v, &v_ref, sizeof v), 0) << p.transpose();
      EXPECT_EQ(std::memcmp(g, g_ref, sizeof g), 0) << p.transpose();
      EXPECT_EQ(std::memcmp(dz.data(), dz_ref.data(), dz.size() * sizeof(double)), 0) << p.transpose();
      const double value_only = lookup.EvaluateDenseValue(dense, p.data());
      EXPECT_EQ(std::memcmp(&value_only, &v_ref, sizeof v), 0) << p.transpose();
    }
    // Around the box: the cell only inside it, and the value-only lookups
    // (EvaluateDenseValue, EvaluateDenseValueOutside for the points outside)
    // equal EvaluateDense's everywhere.
    ShapeLookup::DenseCell cell;
    for (const Eigen::Vector3d& p : RandomPoints(grid, 0.5, 400, 10)) {
      const bool inside = (p.array() >= grid.MinCorner().array()).all() && (p.array() <= grid.MaxCorner().array()).all();
      EXPECT_EQ(lookup.LocateInside(p.data(), &cell), inside) << p.transpose();
      const double v_ref = lookup.EvaluateDense(dense, p.data(), nullptr, nullptr);
      const double v = lookup.EvaluateDenseValue(dense, p.data());
      EXPECT_EQ(std::memcmp(&v, &v_ref, sizeof v), 0) << p.transpose();
      if (!inside) {
        const double v_outside = lookup.EvaluateDenseValueOutside(dense, p.data());
        EXPECT_EQ(std::memcmp(&v_outside, &v_ref, sizeof v), 0) << p.transpose();
      }
    }
    const double nan_point[3] = {std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0};
    EXPECT_FALSE(lookup.LocateInside(nan_point, &cell));
    EXPECT_TRUE(std::isnan(lookup.EvaluateDenseValue(dense, nan_point)));
  }
}

TEST(ShapeLookup, GradientsMatchFiniteDifferencesInsideAndOutside) {
  const ShapeModel model = RandomModel(3, 3);
  const ShapeLookup lookup(model);
  const Eigen::VectorXd z = Eigen::Vector3d(-0.2, 0.9, 1.1);
  const double step = 1e-6;
  int num_outside = 0;
  for (const auto& p : RandomPoints(model.grid, 0.5, 500, 4)) {
    const bool outside =
        !((p.array() >= model.grid.MinCorner().array()).all() &&
          (p.array() <= model.grid.MaxCorner().array()).all());
    num_outside += outside;
    Eigen::Vector3d d_point;
    Eigen::VectorXd d_z;
    const double value = lookup.Evaluate(z, p, &d_point, &d_z);
    EXPECT_EQ(value, lookup.Evaluate(z, p));
    for (int a = 0; a < 3; ++a) {
      Eigen::Vector3d plus = p, minus = p;
      plus[a] += step;
      minus[a] -= step;
      const double numeric = (lookup.Evaluate(z, plus) - lookup.Evaluate(z, minus)) / (2 * step);
      EXPECT_NEAR(d_point[a], numeric, 1e-6 * (1.0 + std::abs(numeric)))
          << "axis " << a << " at " << p.transpose() << (outside ? " (outside)" : "");
    }
    ASSERT_EQ(d_z.size(), 3);
    for (int r = 0; r < 3; ++r) {
      Eigen::VectorXd plus = z, minus = z;
      plus[r] += 1e-3;
      minus[r] -= 1e-3;
      const double numeric = (lookup.Evaluate(plus, p) - lookup.Evaluate(minus, p)) / 2e-3;
      EXPECT_NEAR(d_z[r], numeric, 1e-6) << "component " << r;
    }
    // The raw-pointer and dense paths agree.
    double d_point_raw[3], d_z_raw[3], d_point_dense[3], d_z_dense[3];
    EXPECT_EQ(lookup.Evaluate(z.data(), p.data(), d_point_raw, d_z_raw), value);
    const double* dense = lookup.DenseCached(z.data());
    EXPECT_NEAR(lookup.EvaluateDense(dense, p.data(), d_point_dense, d_z_dense), value, 1e-12);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(d_point_raw[i], d_point[i]);
      EXPECT_EQ(d_z_raw[i], d_z[i]);
      EXPECT_NEAR(d_z_dense[i], d_z[i], 1e-12);
      EXPECT_NEAR(d_point_dense[i], d_point[i], 1e-9);
    }
  }
  EXPECT_GT(num_outside, 100);
  EXPECT_LT(num_outside, 490);
}

TEST(ShapeLookup, FarOutsideGradientPointsAwayFromTheGrid) {
  const ShapeModel model = RandomModel(2, 5);
  const ShapeLookup lookup(model);
  const Eigen::VectorXd z = Eigen::Vector2d(0.3, -0.5);
  const Eigen::Vector3d centre = 0.5 * (model.grid.MinCorner() + model.grid.MaxCorner());
  for (const Eigen::Vector3d offset :
       {Eigen::Vector3d(5, 0, 0), Eigen::Vector3d(0, -4, 0), Eigen::Vector3d(0, 0, 3),
        Eigen::Vector3d(-3, 2, 1), Eigen::Vector3d(2, 2, -2)}) {
    const Eigen::Vector3d p = centre + offset;
    Eigen::Vector3d gradient;
    const double value = lookup.Evaluate(z, p, &gradient);
    EXPECT_GT(gradient.norm(), 0.99);
    EXPECT_GT(gradient.dot(p - centre), 0.0) << offset.transpose();
    // Moving away increases the value by about the distance moved.
    EXPECT_NEAR(lookup.Evaluate(z, p + 0.1 * offset.normalized()) - value, 0.1, 0.05);
  }
  // Straight out of a face: value = the face value plus the distance, gradient = the face normal.
  const Eigen::Vector3d face = model.grid.MaxCorner() - Eigen::Vector3d(0.0, 0.13, 0.17);
  Eigen::Vector3d gradient;
  EXPECT_NEAR(lookup.Evaluate(z, face + Eigen::Vector3d(2.0, 0, 0), &gradient), lookup.Evaluate(z, face) + 2.0,
              1e-9);
  EXPECT_NEAR(gradient.x(), 1.0, 1e-12);
  // Off a corner along a diagonal: distance 5, gradient (0.6, 0.8, 0).
  const Eigen::Vector3d corner = model.grid.MaxCorner();
  EXPECT_NEAR(lookup.Evaluate(z, corner + Eigen::Vector3d(3, 4, 0), &gradient), lookup.Evaluate(z, corner) + 5.0,
              1e-9);
  EXPECT_NEAR(gradient.x(), 0.6, 1e-9);
  EXPECT_NEAR(gradient.y(), 0.8, 1e-9);
}

TEST(ShapeLookup, NonFinitePointGivesNaN) {
  const ShapeModel model = RandomModel(2, 6);
  const ShapeLookup lookup(model);
  const Eigen::VectorXd z = Eigen::Vector2d(0.0, 0.0);
  Eigen::Vector3d d_point;
  Eigen::VectorXd d_z;
  EXPECT_TRUE(std::isnan(lookup.Evaluate(z, Eigen::Vector3d(NAN, 0, 0), &d_point, &d_z)));
  EXPECT_TRUE(std::isnan(d_point[0]));
  EXPECT_TRUE(std::isnan(d_z[1]));
  EXPECT_TRUE(std::isnan(lookup.Evaluate(z, Eigen::Vector3d(0, INFINITY, 0))));
  EXPECT_THROW(lookup.Evaluate(Eigen::Vector3d(1, 2, 3), Eigen::Vector3d::Zero()), Error);
}

TEST(ShapeLookup, RejectsInconsistentModels) {
  ShapeModel model = RandomModel(2, 9);
  model.eigenvalues[1] = 0.0;
  EXPECT_THROW(ShapeLookup{model}, Error);
  model = RandomModel(2, 9);
  model.mean.resize(model.mean.size() - 1);
  EXPECT_THROW(ShapeLookup{model}, Error);
}

TEST(ShapeModel, FileRoundTrip) {
  TempDir dir;
  ShapeModel model = RandomModel(3, 7);
  model.mean[5] = 0.0f;  // background values round-trip too
  model.mean[6] = -0.0f;
  model.components(9, 1) = 0.0f;
  const std::string path = dir.File("model.vdb");
  model.Save(path);
  const ShapeModel loaded = ShapeModel::Load(path);
  EXPECT_EQ(loaded.grid, model.grid);
  EXPECT_EQ(loaded.grid.voxel_size, model.grid.voxel_size);
  EXPECT_TRUE(loaded.mean == model.mean);
  EXPECT_TRUE(loaded.components == model.components);
  EXPECT_TRUE(loaded.eigenvalues == model.eigenvalues);
  EXPECT_EQ(loaded.total_variance, model.total_variance);
  EXPECT_EQ(loaded.training_shapes, model.training_shapes);
  EXPECT_EQ(nlohmann::json::parse(loaded.options_json), nlohmann::json::parse(model.options_json));
  // Lookups agree after the round trip.
  const Eigen::VectorXd z = Eigen::Vector3d(0.1, 0.2, -0.3);
  const ShapeLookup loaded_lookup(loaded), lookup(model);
  for (const auto& p : RandomPoints(model.grid, 0.2, 50, 8)) {
    EXPECT_EQ(loaded_lookup.Evaluate(z, p), lookup.Evaluate(z, p));
  }
  // Overwriting an existing file works and leaves no temporary behind.
  model.Save(path);
  int num_files = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(path).parent_path())) {
    (void)entry;
    ++num_files;
  }
  EXPECT_EQ(num_files, 1);
}

TEST(ShapeModel, VdbPrintListsTheModel) {
  if (std::system("command -v vdb_print > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "vdb_print (libopenvdb-tools) is not installed";
  }
  TempDir dir;
  const std::string path = dir.File("model.vdb");
  RandomModel(2, 9).Save(path);
  const std::string listing = dir.File("listing.txt");
  ASSERT_EQ(std::system(("vdb_print -l -m '" + path + "' > '" + listing + "' 2>&1").c_str()), 0);
  std::ifstream in(listing);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const char* expected : {"mean", "pc_0", "pc_1", "samp_format_version", "samp_eigenvalues"}) {
    EXPECT_NE(text.find(expected), std::string::npos) << expected << " not in:\n" << text;
  }
}

void ExpectLoadError(const std::string& path, const std::string& message_part) {
  try {
    ShapeModel::Load(path);
    ADD_FAILURE() << "no error loading " << path;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(message_part), std::string::npos)
        << "message: " << e.what();
  }
}

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

TEST(ShapeModel, TruncatedFilesGiveErrors) {
  TempDir dir;
  const std::string path = dir.File("model.vdb");
  RandomModel(3, 10).Save(path);
  const std::string bytes = ReadBytes(path);
  ASSERT_GT(bytes.size(), 100u);
  for (const double keep : {0.0, 0.05, 0.3, 0.5, 0.8, 0.95, 0.999}) {
    const std::string truncated = dir.File("truncated.vdb");
    WriteBytes(truncated, bytes.substr(0, size_t(keep * bytes.size())));
    SCOPED_TRACE("kept " + std::to_string(keep));
    EXPECT_THROW(ShapeModel::Load(truncated), Error);
  }
}

TEST(ShapeModel, CorruptFilesGiveErrorsNotCrashes) {
  TempDir dir;
  const std::string path = dir.File("model.vdb");
  RandomModel(3, 11).Save(path);
  const std::string bytes = ReadBytes(path);
  std::mt19937 rng(12);
  int num_errors = 0;
  // Flip bytes all over the file: every load either throws samp::Error or (if
  // the byte did not matter, e.g. padding) returns the identical model.
  const ShapeModel original = ShapeModel::Load(path);
  for (int trial = 0; trial < 60; ++trial) {
    std::string corrupt = bytes;
    const size_t at = size_t(trial) * bytes.size() / 60 + rng() % 7;
    corrupt[std::min(at, bytes.size() - 1)] ^= char(1 + rng() % 255);
    const std::string corrupt_path = dir.File("corrupt.vdb");
    WriteBytes(corrupt_path, corrupt);
    try {
      const ShapeModel loaded = ShapeModel::Load(corrupt_path);
      EXPECT_TRUE(loaded.mean == original.mean && loaded.components == original.components &&
                  loaded.eigenvalues == original.eigenvalues)
          << "byte " << at << " changed the model silently";
    } catch (const Error&) {
      ++num_errors;
    }
  }
  EXPECT_GT(num_errors, 30);
  const std::string text = dir.File("text.vdb");
  WriteBytes(text, "this is not a vdb file\n");
  EXPECT_THROW(ShapeModel::Load(text), Error);
  ExpectLoadError(dir.File("missing.vdb"), "missing.vdb");
}

TEST(ShapeModel, ForeignAndMismatchedVdbFilesGiveErrors) {
  TempDir dir;
  const ShapeModel model = RandomModel(2, 13);
  std::vector<DenseGrid> grids(3);
  grids[0].name = "mean";
  grids[1].name = "pc_0";
  grids[2].name = "pc_1";
  for (auto& g : grids) g.values.assign(size_t(model.NumVoxels()), 0.5f);

  // A .vdb without samp model metadata (e.g. a fog volume).
  const std::string foreign = dir.File("foreign.vdb");
  WriteVdb(foreign, model.grid, {DenseGrid{"density", grids[0].values}}, {});
  ExpectLoadError(foreign, "not a samp model file");
  // A per-model SDF file of the trainer.
  const std::string sdf = dir.File("sdf.vdb");
  WriteVdb(sdf, model.grid, {DenseGrid{"sdf", grids[0].values}}, {{"samp_file_type", "sdf"}});
  ExpectLoadError(sdf, "not a samp model file");

  // Take a valid file's metadata and break one thing at a time.
  const std::string valid = dir.File("valid.vdb");
  model.Save(valid);
  GridSpec spec;
  VdbMetadata meta;
  ReadVdb(valid, &spec, &meta);
  const std::string broken = dir.File("broken.vdb");
  auto write = [&](const std::vector<DenseGrid>& g, VdbMetadata m) { WriteVdb(broken, spec, g, m); };

  VdbMetadata m = meta;
  m["samp_format_version"] = "3";
  write(grids, m);
  ExpectLoadError(broken, "format version 3");

  m = meta;
  m["samp_num_components"] = "3";
  write(grids, m);
  ExpectLoadError(broken, "eigenvalues");

  m = meta;
  m["samp_eigenvalues"] = "[1.0]";
  write(grids, m);
  ExpectLoadError(broken, "1 eigenvalues for 2 components");

  m = meta;
  m["samp_eigenvalues"] = "[1.0, oops";
  write(grids, m);
  ExpectLoadError(broken, "samp_eigenvalues");

  write({grids[0], grids[1]}, meta);
  ExpectLoadError(broken, "'pc_1' is missing");

  // A NaN value does not survive OpenVDB's dense-to-sparse copy: the grid's
  // checksum fails when WriteVdb reads the written file back, so the file is
  // refused before it replaces `broken` (which keeps the previous contents).
  std::vector<DenseGrid> with_nan = grids;
  with_nan[1].values[3] = std::nanf("");
  try {
    write(with_nan, meta);
    ADD_FAILURE() << "a grid with a NaN was written";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("does not read back"), std::string::npos) << e.what();
  }
  ExpectLoadError(broken, "'pc_1' is missing");

  // Valid structure, different values: the checksum catches it.
  write(grids, meta);
  ExpectLoadError(broken, "checksum");
}

}  // namespace
}  // namespace samp
