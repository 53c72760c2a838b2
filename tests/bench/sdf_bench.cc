// SDF benchmark (docs/benchmarks.md, ## SDF): per-model time of ComputeSdf
// for a ~100k-triangle closed mesh on a ~250k-voxel grid at 0.05 m, one
// thread, next to OpenVDB's meshToLevelSet / meshToSignedDistanceField on the
// same mesh and grid; then a sign check on open / non-watertight meshes.
//
//   sdf_bench [--benchmark_filter=...] [--sdf_timing=0] [--sdf_report=0]
//             [--sdf_cad_dir=CACHE_DIR/cars] [--sdf_corpus=0] [--sdf_cad_check=0]
//             [--sdf_sign_check=0]                (runs single-threaded)
//   sdf_bench --sdf_dump=FILE   (ComputeSdf's values of the test meshes, to compare two builds)
// The cracked corpus (docs/sdf.md, "Cracked meshes") runs on the procedural
// bodies and, with --sdf_cad_dir, on every car of the manifest not skipped.
#include <benchmark/benchmark.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <limits>
#include <functional>
#include <random>
#include <string>

#include "libsamp/core/grid_spec.h"
#include "libsamp/core/mesh.h"
#include "libsamp/core/wheels.h"
#include "libsamp/core/error.h"
#include "libsamp/scan/canonical.h"
#include "libsamp/scan/embree_scene.h"
#include "libsamp/scan/mesh_io.h"
#include "libsamp/scan/scanner.h"
#include "libsamp/sdf/sdf.h"
#include "libsamp/sdf/vdb_io.h"
#include "tests/sdf/crack_corpus.h"

namespace samp {
namespace {

// A car-sized ellipsoid (half-extents 2.1 x 0.75 x 0.9 m, bottom at y = 0 in
// the y-down object frame) of 101,760 triangles.
const Eigen::Vector3d kHalf(2.1, 0.75, 0.9);
const Eigen::Vector3d kCenter(0.0, -0.75, 0.0);

Mesh MakeEllipsoid() {
  Mesh mesh = MakeSphereMesh(Eigen::Vector3d::Zero(), 1.0, 160, 320);
  for (auto& v : mesh.vertices) {
    v = (v.cast<double>().cwiseProduct(kHalf) + kCenter).cast<float>();
  }
  return mesh;
}

// Signed distance estimate of the ellipsoid (first order, exact in sign).
double EllipsoidSdf(const Eigen::Vector3d& p) {
  const Eigen::Vector3d q = (p - kCenter).cwiseQuotient(kHalf);
  const double f = q.norm();
  const Eigen::Vector3d gradient = q.cwiseQuotient(kHalf) / std::max(f, 1e-12);
  return (f - 1.0) / std::max(gradient.norm(), 1e-12);
}

GridSpec BenchGrid() {
  const Eigen::Vector3d margin = Eigen::Vector3d::Constant(0.4);
  return GridSpec::FromBox(kCenter - kHalf - margin, kCenter + kHalf + margin, 0.05);
}

openvdb::math::Transform::Ptr VdbTransform(const GridSpec& grid) {
  auto transform = openvdb::math::Transform::createLinearTransform(grid.voxel_size);
  transform->postTranslate(openvdb::Vec3d(grid.origin.x(), grid.origin.y(), grid.origin.z()));
  return transform;
}

struct VdbMesh {
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
};

VdbMesh ToVdb(const Mesh& mesh) {
  VdbMesh out;
  for (const auto& v : mesh.vertices) out.points.emplace_back(v.x(), v.y(), v.z());
  for (const auto& t : mesh.triangles) out.triangles.emplace_back(t.x(), t.y(), t.z());
  return out;
}

struct Scene {
  Mesh mesh;
  ScanResult scan;
  GridSpec grid;
  VdbMesh vdb_mesh;
  float exterior_band_voxels = 0.0f;  // meshToSignedDistanceField bands that cover the grid
  float interior_band_voxels = 0.0f;
};

const Scene& ClosedScene() {
  static const Scene scene = [] {
    Scene s;
    s.mesh = MakeEllipsoid();
    s.scan = ScanMesh(s.mesh, ScanOptions());
    s.grid = BenchGrid();
    s.vdb_mesh = ToVdb(s.mesh);
    s.exterior_band_voxels = float((s.grid.MaxCorner() - s.grid.MinCorner()).norm() / s.grid.voxel_size);
    s.interior_band_voxels = float(kHalf.minCoeff() / s.grid.voxel_size + 2);
    return s;
  }();
  return scene;
}

void BM_ComputeSdf(benchmark::State& state) {
  const Scene& s = ClosedScene();
  Sdf sdf;
  // The stages' wall-clock shares (SdfSummary), averaged over the iterations.
  double band = 0, propagation = 0, carving = 0, closing = 0;
  for (auto _ : state) {
    sdf = ComputeSdf(s.mesh, s.scan, s.grid, SdfOptions(), /*parallel=*/false);
    benchmark::DoNotOptimize(sdf.values.data());
    band += sdf.summary.band_seconds;
    propagation += sdf.summary.propagation_seconds;
    carving += sdf.summary.carving_seconds;
    closing += sdf.summary.closing_seconds;
  }
  const double iterations = std::max<double>(1.0, double(state.iterations()));
  state.counters["band_ms"] = 1e3 * band / iterations;
  state.counters["propagation_ms"] = 1e3 * propagation / iterations;
  state.counters["carving_ms"] = 1e3 * carving / iterations;
  state.counters["closing_ms"] = 1e3 * closing / iterations;
  state.counters["voxels"] = double(s.grid.NumVoxels());
  state.counters["triangles"] = double(s.mesh.triangles.size());
  state.counters["inside_fraction"] = sdf.summary.inside_fraction;
}
BENCHMARK(BM_ComputeSdf)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// The sign before issue 14 (carving alone): what the closing costs.
void BM_ComputeSdfCarvingOnly(benchmark::State& state) {
  const Scene& s = ClosedScene();
  SdfOptions options;
  options.sign = SdfOptions::Sign::kCarving;
  Sdf sdf;
  for (auto _ : state) {
    sdf = ComputeSdf(s.mesh, s.scan, s.grid, options, /*parallel=*/false);
    benchmark::DoNotOptimize(sdf.values.data());
  }
  state.counters["closing_ms"] = 1e3 * sdf.summary.closing_seconds;
}
BENCHMARK(BM_ComputeSdfCarvingOnly)->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_OpenVdbMeshToLevelSet(benchmark::State& state) {
  const Scene& s = ClosedScene();
  const auto transform = VdbTransform(s.grid);
  for (auto _ : state) {
    auto grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, s.vdb_mesh.points,
                                                                   s.vdb_mesh.triangles, 3.0f);
    benchmark::DoNotOptimize(grid.get());
  }
}
BENCHMARK(BM_OpenVdbMeshToLevelSet)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// The dense equivalent of ComputeSdf: bands wide enough to cover the whole grid.
void BM_OpenVdbMeshToSdfWholeGrid(benchmark::State& state) {
  const Scene& s = ClosedScene();
  const auto transform = VdbTransform(s.grid);
  const std::vector<openvdb::Vec4I> no_quads;
  for (auto _ : state) {
    auto grid = openvdb::tools::meshToSignedDistanceField<openvdb::FloatGrid>(
        *transform, s.vdb_mesh.points, s.vdb_mesh.triangles, no_quads, s.exterior_band_voxels,
        s.interior_band_voxels);
    benchmark::DoNotOptimize(grid.get());
  }
}
BENCHMARK(BM_OpenVdbMeshToSdfWholeGrid)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// ---------------------------------------------------------------------------
// Sign check on open / non-watertight meshes.

// Wrong-sign voxels among those at least one voxel away from the truth's surface.
// `counted` includes voxels whose value is 0.
struct SignCount {
  int64_t wrong = 0;
  int64_t counted = 0;
};

template <typename Value, typename Truth>
SignCount CountWrongSigns(const GridSpec& grid, const Value& value, const Truth& truth) {
  SignCount c;
  for (int k = 0; k < grid.dims.z(); ++k) {
    for (int j = 0; j < grid.dims.y(); ++j) {
      for (int i = 0; i < grid.dims.x(); ++i) {
        const double t = truth(grid.Position(i, j, k));
        if (std::abs(t) < grid.voxel_size) continue;
        ++c.counted;
        // A value of (-)0 is on some surface (e.g. a zero-thickness sheet the
        // truth does not model): its sign is irrelevant.
        const double v = value(i, j, k);
        if (std::abs(v) > 1e-6 && (v > 0) != (t > 0)) ++c.wrong;
      }
    }
  }
  return c;
}

// CAD-like defects on the closed ellipsoid: eight separate parts (no shared
// vertices), a third of the triangles flipped, interior geometry (a seat box
// and a floor plane, never seen), and an external zero-thickness sheet (a
// spoiler). Truth: inside the ellipsoid.
Mesh MakeCadLikeMesh() {
  const Mesh ellipsoid = MakeEllipsoid();
  Mesh mesh;
  std::mt19937 rng(11);
  for (int octant = 0; octant < 8; ++octant) {
    Mesh part;
    for (const auto& t : ellipsoid.triangles) {
      const Eigen::Vector3f c =
          (ellipsoid.vertices[size_t(t.x())] + ellipsoid.vertices[size_t(t.y())] +
           ellipsoid.vertices[size_t(t.z())]) / 3.0f - kCenter.cast<float>();
      const int o = (c.x() > 0) + 2 * (c.y() > 0) + 4 * (c.z() > 0);
      if (o != octant) continue;
      const int base = int(part.vertices.size());
      for (int a = 0; a < 3; ++a) part.vertices.push_back(ellipsoid.vertices[size_t(t[a])]);
      if (rng() % 3 == 0) {
        part.triangles.emplace_back(base, base + 2, base + 1);
      } else {
        part.triangles.emplace_back(base, base + 1, base + 2);
      }
    }
    mesh.Append(part);
  }
  mesh.Append(MakeBoxMesh(Eigen::Vector3d(-0.8, -1.0, -0.5), Eigen::Vector3d(0.2, -0.5, 0.5)));
  Mesh plane;
  plane.vertices = {Eigen::Vector3f(-1.2f, -0.4f, -0.5f), Eigen::Vector3f(1.2f, -0.4f, -0.5f),
                    Eigen::Vector3f(1.2f, -0.4f, 0.5f), Eigen::Vector3f(-1.2f, -0.4f, 0.5f)};
  plane.triangles = {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3)};
  mesh.Append(plane);
  Mesh spoiler;  // behind the car, 0.3 m above its top
  spoiler.vertices = {Eigen::Vector3f(-2.3f, -1.8f, -0.7f), Eigen::Vector3f(-1.9f, -1.8f, -0.7f),
                      Eigen::Vector3f(-1.9f, -1.8f, 0.7f), Eigen::Vector3f(-2.3f, -1.8f, 0.7f)};
  spoiler.triangles = {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3)};
  mesh.Append(spoiler);
  return mesh;
}

// An open box (the bottom face y = hi.y missing): by visibility its inside is
// seen through the opening, so every voxel is outside.
const Eigen::Vector3d kBoxLo(-2.0, -1.4, -0.8), kBoxHi(2.0, 0.0, 0.8);
Mesh MakeOpenBox() {
  Mesh mesh = MakeBoxMesh(kBoxLo, kBoxHi);
  mesh.triangles.erase(mesh.triangles.begin() + 6, mesh.triangles.begin() + 8);  // y = hi
  return mesh;
}

// Unsigned distance to the five walls of the open box (the truth is outside
// everywhere; voxels within a voxel of a wall are not counted).
double OpenBoxDistance(const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      if (axis == 1 && side == 1) continue;  // the missing face y = hi
      Eigen::Vector3d q = p.cwiseMax(kBoxLo).cwiseMin(kBoxHi);
      q[axis] = side ? kBoxHi[axis] : kBoxLo[axis];
      best = std::min(best, (p - q).norm());
    }
  }
  return best;
}

// A closed box (kBoxLo..kBoxHi) with a square hole of side `hole` metres in the
// middle of its z = hi face, larger than meshToLevelSet's band. Truth: the
// solid box.
Mesh MakeBoxWithHole(double hole) {
  Mesh mesh = MakeBoxMesh(kBoxLo, kBoxHi);
  // Drop the z = hi face (two triangles whose vertices all have z = hi) ...
  std::vector<Eigen::Vector3i> kept;
  for (const auto& t : mesh.triangles) {
    bool on_face = true;
    for (int a = 0; a < 3; ++a) on_face &= mesh.vertices[size_t(t[a])].z() == float(kBoxHi.z());
    if (!on_face) kept.push_back(t);
  }
  mesh.triangles = kept;
  // ... and put it back as four rectangles around the hole.
  const double cx = 0.5 * (kBoxLo.x() + kBoxHi.x()), cy = 0.5 * (kBoxLo.y() + kBoxHi.y());
  const double x[4] = {kBoxLo.x(), cx - 0.5 * hole, cx + 0.5 * hole, kBoxHi.x()};
  const double y[4] = {kBoxLo.y(), cy - 0.5 * hole, cy + 0.5 * hole, kBoxHi.y()};
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      if (a == 1 && b == 1) continue;  // the hole
      const int base = int(mesh.vertices.size());
      const float z = float(kBoxHi.z());
      mesh.vertices.push_back(Eigen::Vector3f(float(x[a]), float(y[b]), z));
      mesh.vertices.push_back(Eigen::Vector3f(float(x[a + 1]), float(y[b]), z));
      mesh.vertices.push_back(Eigen::Vector3f(float(x[a + 1]), float(y[b + 1]), z));
      mesh.vertices.push_back(Eigen::Vector3f(float(x[a]), float(y[b + 1]), z));
      mesh.triangles.emplace_back(base, base + 1, base + 2);
      mesh.triangles.emplace_back(base, base + 2, base + 3);
    }
  }
  return mesh;
}

double BoxSdf(const Eigen::Vector3d& p) {
  const Eigen::Vector3d center = 0.5 * (kBoxLo + kBoxHi), half = 0.5 * (kBoxHi - kBoxLo);
  const Eigen::Vector3d q = (p - center).cwiseAbs() - half;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

// The ellipsoid body with the triangles whose centroid satisfies `drop` removed.
template <typename Drop>
Mesh EllipsoidWithout(const Drop& drop) {
  const Mesh ellipsoid = MakeEllipsoid();
  Mesh mesh;
  mesh.vertices = ellipsoid.vertices;
  for (const auto& t : ellipsoid.triangles) {
    const Eigen::Vector3f c = (ellipsoid.vertices[size_t(t.x())] + ellipsoid.vertices[size_t(t.y())] +
                               ellipsoid.vertices[size_t(t.z())]) / 3.0f;
    if (!drop(c)) mesh.triangles.push_back(t);
  }
  return mesh;
}

// Interior geometry of a car: two closed seat boxes and a floor sheet.
void AddInterior(Mesh* mesh) {
  mesh->Append(MakeBoxMesh(Eigen::Vector3d(-0.6, -1.0, -0.6), Eigen::Vector3d(0.0, -0.35, -0.1)));
  mesh->Append(MakeBoxMesh(Eigen::Vector3d(-0.6, -1.0, 0.1), Eigen::Vector3d(0.0, -0.35, 0.6)));
  Mesh floor;
  floor.vertices = {Eigen::Vector3f(-1.6f, -0.3f, -0.7f), Eigen::Vector3f(1.6f, -0.3f, -0.7f),
                    Eigen::Vector3f(1.6f, -0.3f, 0.7f), Eigen::Vector3f(-1.6f, -0.3f, 0.7f)};
  floor.triangles = {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3)};
  mesh->Append(floor);
}

// A car-like hull: the ellipsoid with four open wheel arches (holes of
// radius 0.38 m low on its sides) and the bottom open below y = -0.12 (the
// ellipsoid's lowest 0.12 m), plus seats and a floor inside. Truth: the solid
// ellipsoid.
Mesh MakeOpenHull() {
  Mesh mesh = EllipsoidWithout([](const Eigen::Vector3f& c) {
    if (c.y() > -0.12f) return true;  // open bottom
    for (const float x : {-1.3f, 1.3f}) {
      for (const float z : {-0.8f, 0.8f}) {
        if ((c - Eigen::Vector3f(x, -0.25f, z)).norm() < 0.38f) return true;  // wheel arch
      }
    }
    return false;
  });
  AddInterior(&mesh);
  return mesh;
}

// Panels with gaps: the ellipsoid cut by three 0.1 m slits (all around at
// x = -0.7 and x = 0.9, and along the left side at y = -0.75), plus the
// interior. Truth: the solid ellipsoid.
Mesh MakeSlitHull() {
  Mesh mesh = EllipsoidWithout([](const Eigen::Vector3f& c) {
    return std::abs(c.x() + 0.7f) < 0.05f || std::abs(c.x() - 0.9f) < 0.05f ||
           (c.z() > 0.0f && std::abs(c.y() + 0.75f) < 0.05f);
  });
  AddInterior(&mesh);
  return mesh;
}

// Thread CPU time: the figures do not depend on other load on the machine.
double ThreadSeconds() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

template <typename Fn>
double MedianSeconds(int runs, const Fn& fn) {
  std::vector<double> seconds;
  for (int r = 0; r < runs; ++r) {
    const double start = ThreadSeconds();
    fn();
    seconds.push_back(ThreadSeconds() - start);
  }
  std::sort(seconds.begin(), seconds.end());
  return seconds[seconds.size() / 2];
}

void RunTimingSummary() {
  const Scene& closed = ClosedScene();
  const auto transform = VdbTransform(closed.grid);

  // Timing summary (median of 5) and the ratio.
  const double ours = MedianSeconds(5, [&] {
    ComputeSdf(closed.mesh, closed.scan, closed.grid, SdfOptions(), false);
  });
  const double level_set = MedianSeconds(5, [&] {
    openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, closed.vdb_mesh.points,
                                                       closed.vdb_mesh.triangles, 3.0f);
  });
  const double whole = MedianSeconds(3, [&] {
    openvdb::tools::meshToSignedDistanceField<openvdb::FloatGrid>(
        *transform, closed.vdb_mesh.points, closed.vdb_mesh.triangles, {},
        closed.exterior_band_voxels, closed.interior_band_voxels);
  });
  std::printf("\nClosed ellipsoid: %zu triangles, grid %s (%lld voxels), one thread, median thread CPU time\n",
              closed.mesh.triangles.size(), closed.grid.ToString().c_str(),
              static_cast<long long>(closed.grid.NumVoxels()));
  std::printf("  ComputeSdf (whole grid)                    %8.1f ms\n", 1e3 * ours);
  std::printf("  OpenVDB meshToLevelSet (half width 3)      %8.1f ms  (ratio %.2fx)\n",
              1e3 * level_set, level_set / ours);
  std::printf("  OpenVDB meshToSignedDistanceField (grid)   %8.1f ms  (ratio %.2fx)\n",
              1e3 * whole, whole / ours);
}

// What the closing costs: thread CPU medians of the default sign and of the
// carving alone on the closed ellipsoid (same scan, same grid).
void RunSignCost() {
  const Scene& closed = ClosedScene();
  SdfOptions carving;
  carving.sign = SdfOptions::Sign::kCarving;
  double closing_step = 0.0;
  const double with_closing = MedianSeconds(7, [&] {
    closing_step = ComputeSdf(closed.mesh, closed.scan, closed.grid, SdfOptions(), false).summary.closing_seconds;
  });
  const double carving_only = MedianSeconds(7, [&] {
    ComputeSdf(closed.mesh, closed.scan, closed.grid, carving, false);
  });
  std::printf("\nSign cost (closed ellipsoid, %lld voxels, one thread, median thread CPU of 7):\n"
              "  ComputeSdf, carving + closing (default)   %8.1f ms\n"
              "  ComputeSdf, carving alone (kCarving)      %8.1f ms  (closing adds %.1f ms, %.1f %%;"
              " last closing step %.1f ms wall)\n",
              static_cast<long long>(closed.grid.NumVoxels()), 1e3 * with_closing, 1e3 * carving_only,
              1e3 * (with_closing - carving_only), 100.0 * (with_closing / carving_only - 1.0), 1e3 * closing_step);
}

void RunSignCheck() {
  const Scene& closed = ClosedScene();
  const auto transform = VdbTransform(closed.grid);
  struct Case {
    const char* name;
    Mesh mesh;
    std::function<double(const Eigen::Vector3d&)> truth;
  };
  std::vector<Case> cases;
  cases.push_back({"closed ellipsoid", closed.mesh, EllipsoidSdf});
  cases.push_back({"CAD-like soup (parts, flips, interior, sheet)", MakeCadLikeMesh(), EllipsoidSdf});
  cases.push_back({"open box (visibility truth: all outside)", MakeOpenBox(), OpenBoxDistance});
  cases.push_back({"box, 0.8 m hole in a side (truth: solid box)", MakeBoxWithHole(0.8), BoxSdf});
  cases.push_back({"box, 0.3 m hole in a side (truth: solid box)", MakeBoxWithHole(0.3), BoxSdf});
  cases.push_back({"hull, open arches + bottom, seats (solid)", MakeOpenHull(), EllipsoidSdf});
  cases.push_back({"hull, three 0.1 m slits, seats (solid)", MakeSlitHull(), EllipsoidSdf});
  std::printf("\nWrong-sign voxels (|truth| >= 1 voxel), same grid:\n");
  std::printf("  %-48s %12s %12s %14s %10s\n", "mesh", "ComputeSdf", "carving only", "meshToLevelSet",
              "voxels");
  for (size_t index = 0; index < cases.size(); ++index) {
    const Case& c = cases[index];
    const ScanResult scan = index == 0 ? closed.scan : ScanMesh(c.mesh, ScanOptions());
    const Sdf sdf = ComputeSdf(c.mesh, scan, closed.grid, SdfOptions());
    const SignCount ours_count = CountWrongSigns(
        closed.grid, [&](int i, int j, int k) { return sdf.values[size_t(closed.grid.Index(i, j, k))]; },
        c.truth);
    SdfOptions carving_options;
    carving_options.sign = SdfOptions::Sign::kCarving;
    const Sdf carving = ComputeSdf(c.mesh, scan, closed.grid, carving_options);
    const SignCount carving_count = CountWrongSigns(
        closed.grid, [&](int i, int j, int k) { return carving.values[size_t(closed.grid.Index(i, j, k))]; },
        c.truth);
    const VdbMesh vdb_mesh = ToVdb(c.mesh);
    const auto level_set_grid =
        openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, vdb_mesh.points, vdb_mesh.triangles, 3.0f);
    const auto accessor = level_set_grid->getConstAccessor();
    const SignCount vdb_count = CountWrongSigns(
        closed.grid, [&](int i, int j, int k) { return accessor.getValue(openvdb::Coord(i, j, k)); },
        c.truth);
    std::printf("  %-48s %12lld %12lld %14lld %10lld\n", c.name, static_cast<long long>(ours_count.wrong),
                static_cast<long long>(carving_count.wrong), static_cast<long long>(vdb_count.wrong),
                static_cast<long long>(ours_count.counted));
  }
}


// ---------------------------------------------------------------------------
// Real CAD cars (optional: --sdf_cad_dir=DIR, the folder of tools/get_cad_cars.sh
// with cad_manifest.json). No analytic truth: the reference sign of a voxel is
// the majority over kParityDirections ray directions of the parity of the
// number of mesh surfaces (all triangles) each ray from the voxel centre
// crosses. Voxels within one voxel of the surface (by either method's
// distance) and voxels where the vote is close (within 25 %-75 %) are not
// counted.

constexpr int kParityDirections = 32;

// Fraction of directions with an odd number of crossings, per point.
std::vector<float> ParityVotes(const Mesh& mesh, const std::vector<Eigen::Vector3f>& points) {
  const EmbreeScene scene(mesh);
  const std::vector<Eigen::Vector3d> sphere = FibonacciSphere(kParityDirections);
  std::vector<Eigen::Vector3f> origins, directions;
  std::vector<int32_t> owner;
  for (size_t p = 0; p < points.size(); ++p) {
    for (const Eigen::Vector3d& d : sphere) {
      // A slightly irrational tilt keeps rays off edges and axis-aligned faces.
      origins.push_back(points[p]);
      directions.push_back((d + Eigen::Vector3d(0.0123, 0.0071, 0.0037)).normalized().cast<float>());
      owner.push_back(int32_t(p));
    }
  }
  std::vector<int32_t> crossings(points.size() * size_t(kParityDirections), 0);
  std::vector<int32_t> ray_index(origins.size());
  for (size_t r = 0; r < ray_index.size(); ++r) ray_index[r] = int32_t(r);
  std::vector<RayHit> hits;
  for (int round = 0; round < 64 && !origins.empty(); ++round) {
    scene.Intersect(origins, directions, &hits);
    size_t kept = 0;
    for (size_t r = 0; r < origins.size(); ++r) {
      if (!hits[r].Hit()) continue;
      ++crossings[size_t(ray_index[r])];
      origins[kept] = origins[r] + (hits[r].t + 1e-4f) * directions[r];
      directions[kept] = directions[r];
      ray_index[kept] = ray_index[r];
      ++kept;
    }
    origins.resize(kept);
    directions.resize(kept);
    ray_index.resize(kept);
  }
  std::vector<float> votes(points.size(), 0.0f);
  for (size_t r = 0; r < crossings.size(); ++r) {
    if (crossings[r] % 2) votes[r / kParityDirections] += 1.0f / kParityDirections;
  }
  return votes;
}

void RunCadCheck(const std::string& folder) {
  const Manifest manifest = LoadManifest(folder + "/cad_manifest.json");
  std::printf("\nReal CAD cars (%s), grid 0.05 m around each car (+0.3 m), 100-view scans:\n",
              folder.c_str());
  std::printf("reference: majority of %d-direction ray parity (all triangles); counted: |vote - 0.5| >= 0.25\n"
              "and >= 1 voxel from the surface; wrong = sign differs from the reference\n",
              kParityDirections);
  std::printf("  %-16s %5s %6s %8s %10s %10s %9s %9s %9s %9s %9s %7s\n", "car", "skip", "tris", "counted",
              "wrong:ours", "wrong:vdb", "ours!=vdb", "in:ref", "in:ours", "in:vdb", "ambiguous",
              "SDF ms");
  for (const ManifestEntry& entry : manifest.entries) {
    try {
      const Mesh mesh = Canonicalize(LoadMesh(folder + "/" + entry.file), entry.canonicalize).mesh;
      const AlignedBox box = mesh.Bounds();
      const GridSpec grid = GridSpec::FromBox(box.min - Eigen::Vector3d::Constant(0.3),
                                              box.max + Eigen::Vector3d::Constant(0.3), 0.05);
      const ScanResult scan = ScanMesh(mesh, ScanOptions());
      const double start = ThreadSeconds();
      const Sdf sdf = ComputeSdf(mesh, scan, grid, SdfOptions());
      const double sdf_seconds = ThreadSeconds() - start;
      const VdbMesh vdb_mesh = ToVdb(mesh);
      const auto level_set = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(
          *VdbTransform(grid), vdb_mesh.points, vdb_mesh.triangles, 3.0f);
      const auto accessor = level_set->getConstAccessor();
      // Reference votes for the voxels not near the surface.
      const double h = grid.voxel_size;
      std::vector<Eigen::Vector3f> points;
      std::vector<int64_t> voxel;
      std::vector<float> vdb_values;
      for (int k = 0; k < grid.dims.z(); ++k) {
        for (int j = 0; j < grid.dims.y(); ++j) {
          for (int i = 0; i < grid.dims.x(); ++i) {
            const float ours = sdf.values[size_t(grid.Index(i, j, k))];
            const float theirs = accessor.getValue(openvdb::Coord(i, j, k));
            if (std::abs(ours) < h || std::abs(theirs) < h) continue;
            points.push_back(grid.Position(i, j, k).cast<float>());
            voxel.push_back(grid.Index(i, j, k));
            vdb_values.push_back(theirs);
          }
        }
      }
      const std::vector<float> votes = ParityVotes(mesh, points);
      int64_t counted = 0, ambiguous = 0, inside = 0, wrong_ours = 0, wrong_vdb = 0;
      int64_t ours_inside = 0, vdb_inside = 0, disagree = 0;  // among the counted voxels
      for (size_t p = 0; p < points.size(); ++p) {
        if (std::abs(votes[p] - 0.5f) < 0.25f) {
          ++ambiguous;
          continue;
        }
        ++counted;
        const bool reference_inside = votes[p] > 0.5f;
        inside += reference_inside;
        ours_inside += sdf.values[size_t(voxel[p])] < 0;
        vdb_inside += vdb_values[p] < 0;
        disagree += (sdf.values[size_t(voxel[p])] < 0) != (vdb_values[p] < 0);
        wrong_ours += (sdf.values[size_t(voxel[p])] < 0) != reference_inside;
        wrong_vdb += (vdb_values[p] < 0) != reference_inside;
      }
      std::printf("  %-16s %5s %6zu %8lld %10lld %10lld %9lld %9lld %9lld %9lld %9lld %7.1f\n",
                  entry.name.c_str(), entry.skip ? "yes" : "no", mesh.triangles.size(),
                  static_cast<long long>(counted), static_cast<long long>(wrong_ours),
                  static_cast<long long>(wrong_vdb), static_cast<long long>(disagree),
                  static_cast<long long>(inside),
                  static_cast<long long>(ours_inside), static_cast<long long>(vdb_inside),
                  static_cast<long long>(ambiguous), 1e3 * sdf_seconds);
    } catch (const Error& e) {
      std::printf("  %-16s not compared (%s): %s\n", entry.name.c_str(),
                  entry.skip ? "skipped by the manifest" : "error", e.what());
    }
  }
}


// ---------------------------------------------------------------------------
// The cracked corpus: each clean mesh (procedural bodies on wheels; with
// --sdf_cad_dir also every usable real car, canonicalised by the manifest)
// damaged seven ways; wrong-sign voxels against the clean mesh's carving, on
// the training grid (0.1 m, GridSpec::CarDefault), default 100-view scans.
void RunCrackedCorpus(const std::string& cad_dir) {
  std::vector<std::pair<std::string, Mesh>> bodies = {
      {"sedan (procedural)", AddWheels(test::MakeSedanBody(), WheelOptions()).Combined()},
      {"van (procedural)", AddWheels(test::MakeVanBody(), WheelOptions()).Combined()}};
  if (!cad_dir.empty()) {
    const Manifest manifest = LoadManifest(cad_dir + "/cad_manifest.json");
    for (const ManifestEntry& entry : manifest.entries) {
      if (entry.skip) continue;
      try {
        bodies.push_back({entry.name, Canonicalize(LoadMesh(cad_dir + "/" + entry.file), entry.canonicalize).mesh});
      } catch (const Error& e) {
        std::printf("  %s not used: %s\n", entry.name.c_str(), e.what());
      }
    }
  }
  const GridSpec grid = GridSpec::CarDefault();
  SdfOptions carving, closing;
  carving.sign = SdfOptions::Sign::kCarving;
  carving.min_inside_fraction = closing.min_inside_fraction = 0.0;
  std::printf("\nCracked corpus: wrong-sign voxels (>= 1 voxel from the clean surface) as %% of the clean inside,\n"
              "grid %s, against the carving of the clean mesh\n", grid.ToString().c_str());
  std::printf("  %-20s %-10s", "mesh", "inside");
  const std::vector<test::CrackOptions> variants = test::CrackVariants();
  std::printf(" %-13s", "clean");
  for (size_t v = 0; v < variants.size(); ++v) std::printf(" %-13s", ("v" + std::to_string(v + 1)).c_str());
  std::printf("   (each: carving / carving+closing)\n");
  double worst_carving = 0.0, worst_closing = 0.0, closing_ms = 0.0, total_ms = 0.0;
  int runs = 0;
  for (const auto& [name, clean] : bodies) {
    const ScanResult clean_scan = ScanMesh(clean, ScanOptions());
    const Sdf reference = ComputeSdf(clean, clean_scan, grid, carving);
    const Sdf clean_closing = ComputeSdf(clean, clean_scan, grid, closing);
    const test::SignDifference own = test::CompareSigns(grid, reference.values, clean_closing.values);
    std::printf("  %-20s %-10lld %5.2f/%-7.2f", name.c_str(), static_cast<long long>(own.clean_inside), 0.0,
                100.0 * own.Share());
    worst_closing = std::max(worst_closing, own.Share());
    for (const test::CrackOptions& variant : variants) {
      const Mesh cracked = test::CrackMesh(clean, variant);
      const ScanResult scan = ScanMesh(cracked, ScanOptions());
      const Sdf a = ComputeSdf(cracked, scan, grid, carving);
      const Sdf b = ComputeSdf(cracked, scan, grid, closing);
      const double wa = test::CompareSigns(grid, reference.values, a.values).Share();
      const double wb = test::CompareSigns(grid, reference.values, b.values).Share();
      worst_carving = std::max(worst_carving, wa);
      worst_closing = std::max(worst_closing, wb);
      closing_ms += 1e3 * b.summary.closing_seconds;
      total_ms += 1e3 * b.summary.seconds;
      ++runs;
      std::printf(" %5.2f/%-7.2f", 100.0 * wa, 100.0 * wb);
    }
    std::printf("\n");
  }
  std::printf("variants:");
  for (size_t v = 0; v < variants.size(); ++v) std::printf(" v%zu = %s;", v + 1, variants[v].name.c_str());
  std::printf("\nworst: carving %.2f %%, carving+closing %.2f %%; closing step %.2f ms of %.1f ms per SDF (mean of %d)\n",
              100.0 * worst_carving, 100.0 * worst_closing, closing_ms / std::max(1, runs),
              total_ms / std::max(1, runs), runs);
}
// --sdf_dump=FILE: the values of ComputeSdf for the benchmark mesh and the
// sign check's meshes, serial and in slabs, with the carving alone and with
// the closing, as raw floats: `cmp` two builds' files to show that a change
// kept every value.
void DumpValues(const std::string& path) {
  const Scene& closed = ClosedScene();
  const std::vector<Mesh> meshes = {closed.mesh,          MakeCadLikeMesh(), MakeOpenBox(), MakeBoxWithHole(0.8),
                                    MakeBoxWithHole(0.3), MakeOpenHull(),    MakeSlitHull()};
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) {
    std::fprintf(stderr, "sdf_bench: cannot write %s\n", path.c_str());
    std::exit(1);
  }
  for (const Mesh& mesh : meshes) {
    const ScanResult scan = ScanMesh(mesh, ScanOptions());
    for (const bool parallel : {false, true}) {
      for (const SdfOptions::Sign sign : {SdfOptions::Sign::kCarving, SdfOptions::Sign::kCarvingAndClosing}) {
        SdfOptions options;
        options.sign = sign;
        const Sdf sdf = ComputeSdf(mesh, scan, closed.grid, options, parallel);
        std::fwrite(sdf.values.data(), sizeof(float), sdf.values.size(), file);
      }
    }
  }
  std::fclose(file);
  std::printf("wrote %zu meshes x 4 configurations of %lld values to %s\n", meshes.size(),
              (long long)closed.grid.NumVoxels(), path.c_str());
}
}  // namespace
}  // namespace samp

int main(int argc, char** argv) {
  // One thread for everything, OpenVDB's TBB loops included.
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  samp::InitializeOpenVdb();
  // Own flags (removed before Google Benchmark parses the rest):
  //   --sdf_report=0      skip everything after the benchmarks (e.g. for profiling)
  //   --sdf_timing=0      skip the timing summary (OpenVDB's whole-grid SDF takes ~1 min)
  //   --sdf_cad_dir=DIR   also compare signs on the real CAD cars in DIR
  //   --sdf_dump=FILE     only write ComputeSdf's values of the test meshes (DumpValues)
  bool report = true, timing = true, corpus = true, cad_check = true, sign_check = true;
  std::string cad_dir;
  int kept = 1;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--sdf_report=0") {
      report = false;
    } else if (arg == "--sdf_timing=0") {
      timing = false;
    } else if (arg == "--sdf_corpus=0") {
      corpus = false;
    } else if (arg == "--sdf_cad_check=0") {
      cad_check = false;
    } else if (arg == "--sdf_sign_check=0") {
      sign_check = false;
    } else if (arg.rfind("--sdf_dump=", 0) == 0) {
      samp::DumpValues(arg.substr(std::string("--sdf_dump=").size()));
      return 0;
    } else if (arg.rfind("--sdf_cad_dir=", 0) == 0) {
      cad_dir = arg.substr(std::string("--sdf_cad_dir=").size());
    } else {
      argv[kept++] = argv[a];
    }
  }
  argc = kept;
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  if (report && timing) samp::RunTimingSummary();
  if (report) samp::RunSignCost();
  if (report && sign_check) samp::RunSignCheck();
  if (report && cad_check && !cad_dir.empty()) samp::RunCadCheck(cad_dir);
  if (report && corpus) samp::RunCrackedCorpus(cad_dir);
  return 0;
}
