// Scanner and renderer throughput (docs/benchmarks.md, "## Scanner").
//   scan_bench --benchmark_counters_tabular=true
// ScanMesh and IntersectCamera run on one thread (TBB limited to 1 for the
// whole process), so "rays_per_s" is per core. Render uses all cores.
#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "libsamp/scan/embree_scene.h"
#include "libsamp/scan/renderer.h"
#include "libsamp/scan/scanner.h"

namespace samp {
namespace {

// A bumpy car-sized ellipsoid (4.4 x 1.5 x 1.8 m) on an n x n UV sphere.
Mesh MakeBumpyMesh(int n) {
  Mesh m = MakeSphereMesh(Eigen::Vector3d::Zero(), 1.0, n, n);
  for (Eigen::Vector3f& v : m.vertices) {
    const float bump = 1.f + 0.06f * std::sin(9.f * v.x()) * std::sin(11.f * v.y()) * std::sin(13.f * v.z());
    v = Eigen::Vector3f(2.2f * v.x(), 0.75f * v.y(), 0.9f * v.z()) * bump;
  }
  return m;
}

// ~100k triangles (224 x 224).
const Mesh& BumpyMesh() {
  static const Mesh mesh = MakeBumpyMesh(224);
  return mesh;
}

void BM_ScanMesh(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  ScanOptions options;  // defaults: 100 views of 400 x 400
  options.num_views = int(state.range(0));
  int64_t rays = 0;
  for (auto _ : state) {
    const ScanResult result = ScanMesh(BumpyMesh(), options);
    rays += result.num_rays;
    benchmark::DoNotOptimize(result.num_hits);
  }
  state.counters["triangles"] = double(BumpyMesh().triangles.size());
  state.counters["rays_per_s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ScanMesh)->Arg(100)->Unit(benchmark::kMillisecond);

PinholeCamera ViewCamera() {
  PinholeCamera camera;
  camera.width = camera.height = 400;
  camera.fx = camera.fy = 200.0 / std::tan(20.0 * M_PI / 180.0);
  camera.cx = camera.cy = 199.5;
  return camera;
}

// View k of 64 around the mesh, as the scanner places them.
Eigen::Isometry3d View(size_t k) {
  static const std::vector<Eigen::Vector3d> directions = FibonacciSphere(64);
  static const double radius = 0.5 * BumpyMesh().Bounds().Size().norm();
  const Eigen::Vector3d eye = 3.2 * radius * directions[k % directions.size()];
  const Eigen::Vector3d z = -eye.normalized();
  Eigen::Vector3d reference = Eigen::Vector3d::UnitY();
  if (std::abs(z.dot(reference)) > 0.99) reference = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d x = reference.cross(z).normalized();
  Eigen::Isometry3d object_from_camera = Eigen::Isometry3d::Identity();
  object_from_camera.linear() << x, z.cross(x), z;
  object_from_camera.translation() = eye;
  return object_from_camera;
}

// The ray casting alone as the scanner does it (depth and triangle images of
// one 400 x 400 view), without the scene build.
void BM_IntersectCamera(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const EmbreeScene scene(BumpyMesh());
  const PinholeCamera camera = ViewCamera();
  std::vector<float> depth(400 * 400);
  std::vector<int32_t> triangle(400 * 400);
  EmbreeScene::ImageOutputs outputs;
  outputs.depth = depth.data();
  outputs.triangle = triangle.data();
  int64_t rays = 0;
  size_t k = 0;
  for (auto _ : state) {
    scene.IntersectCameraImage(camera, View(k++), 0, 400, outputs);
    rays += 400 * 400;
  }
  state.counters["packet"] = scene.PacketSize();
  state.counters["rays_per_s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_IntersectCamera)->Unit(benchmark::kMillisecond);

// Reference: the same views with Embree's C API directly, nothing stored, to
// show the wrapper's overhead in the same run and to compare Embree's options.
// The ray directions of each view are computed before its timing starts, so
// the time is Embree's (plus copying 3 x N floats into each packet).
// Args: packet width (16, 8, 4, or 1 = rtcIntersect1M stream of one tile
// row-major 16 x 16), build quality (0 low, 1 medium, 2 high), robust (0/1),
// coherent context flag (0/1).
template <int N>
struct RawPacket;
template <>
struct RawPacket<4> {
  using Type = RTCRayHit4;
  static constexpr int kTw = 2, kTh = 2;
  static void Intersect(const int* valid, RTCScene s, RTCIntersectContext* c, Type* r) { rtcIntersect4(valid, s, c, r); }
};
template <>
struct RawPacket<8> {
  using Type = RTCRayHit8;
  static constexpr int kTw = 4, kTh = 2;
  static void Intersect(const int* valid, RTCScene s, RTCIntersectContext* c, Type* r) { rtcIntersect8(valid, s, c, r); }
};
template <>
struct RawPacket<16> {
  using Type = RTCRayHit16;
  static constexpr int kTw = 4, kTh = 4;
  static void Intersect(const int* valid, RTCScene s, RTCIntersectContext* c, Type* r) { rtcIntersect16(valid, s, c, r); }
};

struct RawScene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  RawScene(const Mesh& mesh, RTCBuildQuality quality, bool robust) {
    device = rtcNewDevice(nullptr);
    scene = rtcNewScene(device);
    if (robust) rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene, quality);
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geometry, quality);
    float* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, mesh.vertices.size()));
    unsigned* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, mesh.triangles.size()));
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
      for (int c = 0; c < 3; ++c) vertices[3 * i + c] = mesh.vertices[i][c];
    }
    for (size_t i = 0; i < mesh.triangles.size(); ++i) {
      for (int c = 0; c < 3; ++c) indices[3 * i + c] = unsigned(mesh.triangles[i][c]);
    }
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene, geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(scene);
  }
  ~RawScene() {
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
  }
};

// Unit ray directions of one 400 x 400 view, grouped by tiles of tw x th
// pixels (row-major within a tile), the tiles row-major.
std::vector<Eigen::Vector3f> TileDirections(const Eigen::Isometry3f& view, int tw, int th) {
  const PinholeCamera camera = ViewCamera();
  std::vector<Eigen::Vector3f> directions;
  directions.reserve(400 * 400);
  for (int v0 = 0; v0 < 400; v0 += th) {
    for (int u0 = 0; u0 < 400; u0 += tw) {
      for (int j = 0; j < tw * th; ++j) {
        directions.push_back(view.linear() * Eigen::Vector3f((u0 + j % tw - 199.5f) / float(camera.fx),
                                                             (v0 + j / tw - 199.5f) / float(camera.fy), 1.f)
                                                 .normalized());
      }
    }
  }
  return directions;
}

template <int N>
int64_t TraceRawView(RTCScene scene, RTCIntersectContext* context, const Eigen::Vector3f& origin,
                     const std::vector<Eigen::Vector3f>& directions) {
  using P = RawPacket<N>;
  alignas(64) typename P::Type packet;
  alignas(64) int valid[N];
  for (int j = 0; j < N; ++j) {
    valid[j] = -1;
    packet.ray.org_x[j] = origin.x();
    packet.ray.org_y[j] = origin.y();
    packet.ray.org_z[j] = origin.z();
    packet.ray.tnear[j] = 0.f;
    packet.ray.mask[j] = ~0u;
    packet.ray.flags[j] = 0;
    packet.ray.time[j] = 0.f;
    packet.ray.id[j] = unsigned(j);
    packet.hit.instID[0][j] = RTC_INVALID_GEOMETRY_ID;
  }
  int64_t hits = 0;
  for (size_t begin = 0; begin < directions.size(); begin += N) {
    for (int j = 0; j < N; ++j) {
      const Eigen::Vector3f& d = directions[begin + size_t(j)];
      packet.ray.dir_x[j] = d.x();
      packet.ray.dir_y[j] = d.y();
      packet.ray.dir_z[j] = d.z();
      packet.ray.tfar[j] = std::numeric_limits<float>::infinity();
      packet.hit.geomID[j] = RTC_INVALID_GEOMETRY_ID;
    }
    P::Intersect(valid, scene, context, &packet);
    for (int j = 0; j < N; ++j) hits += packet.hit.geomID[j] != RTC_INVALID_GEOMETRY_ID;
  }
  return hits;
}

// rtcIntersect1M over a stream of 256 rays (a 16 x 16 tile).
int64_t TraceRawStream(RTCScene scene, RTCIntersectContext* context, const Eigen::Vector3f& origin,
                       const std::vector<Eigen::Vector3f>& directions) {
  constexpr int kStream = 256;
  std::vector<RTCRayHit> rays(kStream);
  int64_t hits = 0;
  for (size_t begin = 0; begin < directions.size(); begin += kStream) {
    const int n = int(std::min<size_t>(kStream, directions.size() - begin));
    for (int j = 0; j < n; ++j) {
      RTCRayHit& r = rays[size_t(j)];
      const Eigen::Vector3f& d = directions[begin + size_t(j)];
      r.ray.org_x = origin.x();
      r.ray.org_y = origin.y();
      r.ray.org_z = origin.z();
      r.ray.dir_x = d.x();
      r.ray.dir_y = d.y();
      r.ray.dir_z = d.z();
      r.ray.tnear = 0.f;
      r.ray.tfar = std::numeric_limits<float>::infinity();
      r.ray.mask = ~0u;
      r.ray.flags = 0;
      r.ray.time = 0.f;
      r.ray.id = unsigned(j);
      r.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      r.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect1M(scene, context, rays.data(), unsigned(n), sizeof(RTCRayHit));
    for (int j = 0; j < n; ++j) hits += rays[size_t(j)].hit.geomID != RTC_INVALID_GEOMETRY_ID;
  }
  return hits;
}

void BM_EmbreeRawPackets(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const int width = int(state.range(0));
  const RawScene raw(BumpyMesh(), RTCBuildQuality(state.range(1)), state.range(2) != 0);
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = state.range(3) ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  const int tw = width == 16 ? 4 : width == 8 ? 4 : width == 4 ? 2 : 16;
  const int th = width == 16 ? 4 : width == 8 ? 2 : width == 4 ? 2 : 16;
  int64_t rays = 0, hits = 0;
  size_t k = 0;
  for (auto _ : state) {
    state.PauseTiming();
    const Eigen::Isometry3f view = View(k++).cast<float>();
    const std::vector<Eigen::Vector3f> directions = TileDirections(view, tw, th);
    state.ResumeTiming();
    switch (width) {
      case 16: hits += TraceRawView<16>(raw.scene, &context, view.translation(), directions); break;
      case 8: hits += TraceRawView<8>(raw.scene, &context, view.translation(), directions); break;
      case 4: hits += TraceRawView<4>(raw.scene, &context, view.translation(), directions); break;
      default: hits += TraceRawStream(raw.scene, &context, view.translation(), directions); break;
    }
    rays += 400 * 400;
  }
  state.counters["hit_fraction"] = double(hits) / double(std::max<int64_t>(rays, 1));
  state.counters["rays_per_s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
}
// The configuration EmbreeScene uses (packets of 16, high quality, robust, coherent) ...
BENCHMARK(BM_EmbreeRawPackets)->Args({16, 2, 1, 1})->Unit(benchmark::kMillisecond);
// ... and the alternatives: packet width / stream, build quality, robust, coherent flag.
BENCHMARK(BM_EmbreeRawPackets)
    ->ArgNames({"packet", "quality", "robust", "coherent"})
    ->Args({8, 2, 1, 1})
    ->Args({4, 2, 1, 1})
    ->Args({1, 2, 1, 1})
    ->Args({16, 1, 1, 1})
    ->Args({16, 0, 1, 1})
    ->Args({16, 2, 0, 1})
    ->Args({16, 2, 1, 0})
    ->Unit(benchmark::kMillisecond);

void BM_SceneBuild(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  for (auto _ : state) {
    const EmbreeScene scene(BumpyMesh());
    benchmark::DoNotOptimize(&scene);
  }
  state.counters["triangles"] = double(BumpyMesh().triangles.size());
}
BENCHMARK(BM_SceneBuild)->Unit(benchmark::kMillisecond);

// Embree's BVH build alone at each build quality (0 low, 1 medium, 2 high), robust.
void BM_EmbreeRawBuild(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  for (auto _ : state) {
    const RawScene raw(BumpyMesh(), RTCBuildQuality(state.range(0)), true);
    benchmark::DoNotOptimize(raw.scene);
  }
}
BENCHMARK(BM_EmbreeRawBuild)->ArgName("quality")->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// A KITTI-sized frame (1242 x 375) of the mesh 10 m ahead, all cores. Arg:
// n of the n x n sphere (224: 100k triangles; 50: 5k, the size of a CAD car).
void BM_Render(benchmark::State& state) {
  const PinholeCamera camera;  // KITTI defaults
  const Mesh mesh = MakeBumpyMesh(int(state.range(0)));
  PlacedMesh placed{&mesh, Eigen::Isometry3d::Identity()};
  placed.camera_from_object.translation() = Eigen::Vector3d(0, 0.8, 10);
  int64_t rays = 0;
  for (auto _ : state) {
    const RenderBuffers buffers = Render(camera, {placed});
    benchmark::DoNotOptimize(buffers.depth.data());
    rays += int64_t(camera.width) * camera.height;
  }
  state.counters["triangles"] = double(mesh.triangles.size());
  state.counters["rays_per_s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Render)->Arg(224)->Arg(50)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace samp

BENCHMARK_MAIN();
