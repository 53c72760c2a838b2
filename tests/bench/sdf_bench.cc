// SDF benchmark (docs/benchmarks.md, ## SDF): per-model time of ComputeSdf
// for a ~100k-triangle closed mesh on a ~250k-voxel grid at 0.05 m, one
// thread, next to OpenVDB's meshToLevelSet / meshToSignedDistanceField on the
// same mesh and grid; then a sign check on open / non-watertight meshes.
//
//   sdf_bench [--benchmark_filter=...]        (runs single-threaded)
#include <benchmark/benchmark.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <functional>
#include <random>
#include <string>

#include "libsamp/core/grid_spec.h"
#include "libsamp/core/mesh.h"
#include "libsamp/scan/scanner.h"
#include "libsamp/sdf/sdf.h"
#include "libsamp/sdf/vdb_io.h"

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
  for (auto _ : state) {
    sdf = ComputeSdf(s.mesh, s.scan, s.grid, SdfOptions(), /*parallel=*/false);
    benchmark::DoNotOptimize(sdf.values.data());
  }
  state.counters["voxels"] = double(s.grid.NumVoxels());
  state.counters["triangles"] = double(s.mesh.triangles.size());
  state.counters["inside_fraction"] = sdf.summary.inside_fraction;
}
BENCHMARK(BM_ComputeSdf)->Unit(benchmark::kMillisecond)->MinTime(2.0);

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

void RunSignCheck() {
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

  struct Case {
    const char* name;
    Mesh mesh;
    std::function<double(const Eigen::Vector3d&)> truth;
  };
  std::vector<Case> cases;
  cases.push_back({"closed ellipsoid", closed.mesh, EllipsoidSdf});
  cases.push_back({"CAD-like soup (parts, flips, interior, sheet)", MakeCadLikeMesh(), EllipsoidSdf});
  cases.push_back({"open box (visibility truth: all outside)", MakeOpenBox(), OpenBoxDistance});
  std::printf("\nWrong-sign voxels (|truth| >= 1 voxel), same grid:\n");
  std::printf("  %-48s %12s %14s %10s\n", "mesh", "ComputeSdf", "meshToLevelSet", "voxels");
  for (size_t index = 0; index < cases.size(); ++index) {
    const Case& c = cases[index];
    const ScanResult scan = index == 0 ? closed.scan : ScanMesh(c.mesh, ScanOptions());
    const Sdf sdf = ComputeSdf(c.mesh, scan, closed.grid, SdfOptions());
    const SignCount ours_count = CountWrongSigns(
        closed.grid, [&](int i, int j, int k) { return sdf.values[size_t(closed.grid.Index(i, j, k))]; },
        c.truth);
    const VdbMesh vdb_mesh = ToVdb(c.mesh);
    const auto level_set_grid =
        openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, vdb_mesh.points, vdb_mesh.triangles, 3.0f);
    const auto accessor = level_set_grid->getConstAccessor();
    const SignCount vdb_count = CountWrongSigns(
        closed.grid, [&](int i, int j, int k) { return accessor.getValue(openvdb::Coord(i, j, k)); },
        c.truth);
    std::printf("  %-48s %12lld %14lld %10lld\n", c.name, static_cast<long long>(ours_count.wrong),
                static_cast<long long>(vdb_count.wrong), static_cast<long long>(ours_count.counted));
  }
}

}  // namespace
}  // namespace samp

int main(int argc, char** argv) {
  // One thread for everything, OpenVDB's TBB loops included.
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  samp::InitializeOpenVdb();
  // --sdf_report=0 skips the comparison table and sign check (e.g. for profiling).
  bool report = true;
  for (int a = 1; a < argc; ++a) {
    if (std::string(argv[a]) == "--sdf_report=0") {
      report = false;
      for (int b = a; b + 1 < argc; ++b) argv[b] = argv[b + 1];
      --argc;
      break;
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  if (report) samp::RunSignCheck();
  return 0;
}
