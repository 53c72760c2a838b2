// Scanner and renderer throughput (docs/benchmarks.md, "## Scanner").
//   scan_bench --benchmark_counters_tabular=true
// ScanMesh and IntersectCamera run on one thread (TBB limited to 1 for the
// whole process), so "rays_per_s" is per core. Render uses all cores.
#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <tbb/global_control.h>

#include <cmath>

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

// Reference: the same views with Embree's C API directly (robust scene, high
// build quality, rtcIntersect16 on 4x4 tiles, nothing stored), to show the
// wrapper's overhead in the same run.
void BM_EmbreeRawPackets(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const Mesh& mesh = BumpyMesh();
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene scene = rtcNewScene(device);
  rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
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
  const PinholeCamera camera = ViewCamera();
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  int64_t rays = 0, hits = 0;
  size_t k = 0;
  for (auto _ : state) {
    const Eigen::Isometry3f view = View(k++).cast<float>();
    for (int v0 = 0; v0 < 400; v0 += 4) {
      for (int u0 = 0; u0 < 400; u0 += 4) {
        alignas(64) RTCRayHit16 packet;
        alignas(64) int valid[16];
        for (int j = 0; j < 16; ++j) {
          const Eigen::Vector3f d =
              view.linear() * Eigen::Vector3f((u0 + j % 4 - 199.5f) / float(camera.fx),
                                              (v0 + j / 4 - 199.5f) / float(camera.fy), 1.f)
                                  .normalized();
          valid[j] = -1;
          packet.ray.org_x[j] = view.translation().x();
          packet.ray.org_y[j] = view.translation().y();
          packet.ray.org_z[j] = view.translation().z();
          packet.ray.dir_x[j] = d.x();
          packet.ray.dir_y[j] = d.y();
          packet.ray.dir_z[j] = d.z();
          packet.ray.tnear[j] = 0.f;
          packet.ray.tfar[j] = std::numeric_limits<float>::infinity();
          packet.ray.mask[j] = ~0u;
          packet.ray.flags[j] = 0;
          packet.ray.time[j] = 0.f;
          packet.hit.geomID[j] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect16(valid, scene, &context, &packet);
        for (int j = 0; j < 16; ++j) hits += packet.hit.geomID[j] != RTC_INVALID_GEOMETRY_ID;
      }
    }
    rays += 400 * 400;
  }
  benchmark::DoNotOptimize(hits);
  rtcReleaseScene(scene);
  rtcReleaseDevice(device);
  state.counters["hit_fraction"] = double(hits) / double(std::max<int64_t>(rays, 1));
  state.counters["rays_per_s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_EmbreeRawPackets)->Unit(benchmark::kMillisecond);

void BM_SceneBuild(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  for (auto _ : state) {
    const EmbreeScene scene(BumpyMesh());
    benchmark::DoNotOptimize(&scene);
  }
  state.counters["triangles"] = double(BumpyMesh().triangles.size());
}
BENCHMARK(BM_SceneBuild)->Unit(benchmark::kMillisecond);

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
