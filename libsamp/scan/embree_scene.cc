#include "libsamp/scan/embree_scene.h"

#include <embree3/rtcore.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <mutex>
#include <string>

#include "libsamp/core/error.h"

namespace samp {
namespace {

const char* ErrorName(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_UNKNOWN: return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
  }
  return "unrecognised error code";
}

// Packet types and intersectors of Embree, by width, with the tile shape of
// the camera rays of one packet.
template <typename RayHit, void (*kIntersect)(const int*, RTCScene, RTCIntersectContext*, RayHit*), int kWidth,
          int kHeight>
struct PacketOf {
  using Type = RayHit;
  static void Intersect(const int* valid, RTCScene scene, RTCIntersectContext* context, Type* rays) {
    kIntersect(valid, scene, context, rays);
  }
  static constexpr int kTileWidth = kWidth, kTileHeight = kHeight;
};
template <int N>
struct Packet;
template <>
struct Packet<4> : PacketOf<RTCRayHit4, rtcIntersect4, 2, 2> {};
template <>
struct Packet<8> : PacketOf<RTCRayHit8, rtcIntersect8, 4, 2> {};
template <>
struct Packet<16> : PacketOf<RTCRayHit16, rtcIntersect16, 4, 4> {};

// Unit geometric normal of lane j of a packet, flipped to face the ray origin.
template <typename PacketType>
Eigen::Vector3f FacingNormal(const PacketType& packet, int j) {
  Eigen::Vector3f normal(packet.hit.Ng_x[j], packet.hit.Ng_y[j], packet.hit.Ng_z[j]);
  const float norm = normal.norm();
  if (norm > 0.f) normal /= norm;
  const float dot = normal.x() * packet.ray.dir_x[j] + normal.y() * packet.ray.dir_y[j] +
                    normal.z() * packet.ray.dir_z[j];
  return dot > 0.f ? Eigen::Vector3f(-normal) : normal;
}

// Casts `num_rays` rays in packets of N. `ray(i, &origin, &direction)` gives
// ray i (direction unit length); `out(i)` is where its hit goes.
template <int N, typename RayFn, typename OutFn>
void TracePackets(RTCScene scene, int64_t num_rays, float t_far, bool coherent, const RayFn& ray,
                  const OutFn& out) {
  using P = Packet<N>;
  alignas(64) typename P::Type packet;
  alignas(64) int valid[N];
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  Eigen::Vector3f origin = Eigen::Vector3f::Zero(), direction = Eigen::Vector3f::UnitZ();
  for (int64_t begin = 0; begin < num_rays; begin += N) {
    const int count = int(std::min<int64_t>(N, num_rays - begin));
    for (int j = 0; j < N; ++j) {
      if (j < count) {
        ray(begin + j, &origin, &direction);
        valid[j] = -1;
      } else {
        valid[j] = 0;
      }
      packet.ray.org_x[j] = origin.x();
      packet.ray.org_y[j] = origin.y();
      packet.ray.org_z[j] = origin.z();
      packet.ray.dir_x[j] = direction.x();
      packet.ray.dir_y[j] = direction.y();
      packet.ray.dir_z[j] = direction.z();
      packet.ray.tnear[j] = 0.f;
      packet.ray.tfar[j] = t_far;
      packet.ray.time[j] = 0.f;
      packet.ray.mask[j] = ~0u;
      packet.ray.id[j] = unsigned(j);
      packet.ray.flags[j] = 0;
      packet.hit.geomID[j] = RTC_INVALID_GEOMETRY_ID;
      packet.hit.instID[0][j] = RTC_INVALID_GEOMETRY_ID;
    }
    P::Intersect(valid, scene, &context, &packet);
    for (int j = 0; j < count; ++j) {
      RayHit& hit = out(begin + j);
      if (packet.hit.geomID[j] == RTC_INVALID_GEOMETRY_ID) {
        hit = RayHit();
        continue;
      }
      hit.t = packet.ray.tfar[j];
      hit.geometry = int(packet.hit.geomID[j]);
      hit.triangle = int(packet.hit.primID[j]);
      hit.normal = FacingNormal(packet, j);
    }
  }
}

}  // namespace

struct EmbreeScene::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  int packet_size = 4;
  // Bounds of every vertex of the scene (empty when it has none).
  Eigen::AlignedBox3d bounds;
  std::mutex error_mutex;
  std::string error;  // first error reported by the callback since the last check

  static void OnError(void* user, RTCError code, const char* message) {
    Impl* impl = static_cast<Impl*>(user);
    std::lock_guard<std::mutex> lock(impl->error_mutex);
    if (impl->error.empty()) {
      impl->error = std::string(ErrorName(code)) + (message ? std::string(": ") + message : "");
    }
  }

  // Throws samp::Error when the callback recorded an error during `what`.
  void ThrowIfError(const char* what) {
    std::string message;
    {
      std::lock_guard<std::mutex> lock(error_mutex);
      message.swap(error);
    }
    if (message.empty() && device != nullptr) {
      const RTCError code = rtcGetDeviceError(device);
      if (code != RTC_ERROR_NONE) message = ErrorName(code);
    }
    SAMP_CHECK(message.empty()) << "Embree error in " << what << ": " << message;
  }

  ~Impl() {
    if (scene != nullptr) rtcReleaseScene(scene);
    if (device != nullptr) rtcReleaseDevice(device);
  }
};

namespace {
// An Embree geometry reference released on scope exit (the scene keeps its own).
struct GeometryRelease {
  void operator()(RTCGeometry geometry) const {
    if (geometry != nullptr) rtcReleaseGeometry(geometry);
  }
};
using GeometryHandle = std::unique_ptr<RTCGeometryTy, GeometryRelease>;
}  // namespace

EmbreeScene::EmbreeScene(const std::vector<const Mesh*>& meshes) : impl_(std::make_unique<Impl>()) {
  impl_->device = rtcNewDevice(nullptr);
  if (impl_->device == nullptr) {
    SAMP_THROW() << "cannot create an Embree device: " << ErrorName(rtcGetDeviceError(nullptr));
  }
  rtcSetDeviceErrorFunction(impl_->device, &Impl::OnError, impl_.get());
  if (rtcGetDeviceProperty(impl_->device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED)) {
    impl_->packet_size = 16;
  } else if (rtcGetDeviceProperty(impl_->device, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED)) {
    impl_->packet_size = 8;
  } else {
    impl_->packet_size = 4;
  }

  impl_->scene = rtcNewScene(impl_->device);
  impl_->ThrowIfError("rtcNewScene");
  // Robust traversal: rays through shared edges/vertices never slip between triangles.
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);

  for (size_t id = 0; id < meshes.size(); ++id) {
    const Mesh* mesh = meshes[id];
    if (mesh == nullptr || mesh->Empty()) continue;  // keeps ids = indices; nothing to hit
    const int64_t num_vertices = int64_t(mesh->vertices.size());
    for (const Eigen::Vector3i& t : mesh->triangles) {
      SAMP_CHECK((t.array() >= 0).all() && (t.array().cast<int64_t>() < num_vertices).all())
          << "EmbreeScene: mesh " << id << " has a triangle index out of range";
    }
    // Owned until the scene holds it: every throw below releases it.
    const GeometryHandle geometry(rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE));
    impl_->ThrowIfError("rtcNewGeometry");
    SAMP_CHECK(geometry != nullptr) << "EmbreeScene: cannot create a geometry for mesh " << id;
    // Embree copies into buffers it owns; they outlive `mesh`.
    float* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry.get(), RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
        num_vertices));
    unsigned* indices = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(geometry.get(), RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(unsigned), mesh->triangles.size()));
    if (vertices == nullptr || indices == nullptr) {
      impl_->ThrowIfError("rtcSetNewGeometryBuffer");
      SAMP_THROW() << "EmbreeScene: cannot allocate geometry buffers for mesh " << id;
    }
    for (int64_t v = 0; v < num_vertices; ++v) {
      const Eigen::Vector3f& p = mesh->vertices[v];
      SAMP_CHECK(p.allFinite()) << "EmbreeScene: mesh " << id << " has a non-finite vertex";
      impl_->bounds.extend(p.cast<double>());
      vertices[3 * v + 0] = p.x();
      vertices[3 * v + 1] = p.y();
      vertices[3 * v + 2] = p.z();
    }
    for (size_t f = 0; f < mesh->triangles.size(); ++f) {
      for (int c = 0; c < 3; ++c) indices[3 * f + c] = unsigned(mesh->triangles[f][c]);
    }
    rtcCommitGeometry(geometry.get());
    rtcAttachGeometryByID(impl_->scene, geometry.get(), unsigned(id));
    impl_->ThrowIfError("adding a triangle mesh");
  }
  rtcCommitScene(impl_->scene);
  impl_->ThrowIfError("rtcCommitScene");
}

EmbreeScene::~EmbreeScene() = default;

int EmbreeScene::PacketSize() const { return impl_->packet_size; }

namespace {

template <int N>
void IntersectRays(RTCScene scene, const std::vector<Eigen::Vector3f>& origins,
                   const std::vector<Eigen::Vector3f>& directions, float t_far, RayHit* hits) {
  TracePackets<N>(
      scene, int64_t(origins.size()), t_far, /*coherent=*/false,
      [&](int64_t i, Eigen::Vector3f* origin, Eigen::Vector3f* direction) {
        *origin = origins[i];
        *direction = directions[i];
      },
      [&](int64_t i) -> RayHit& { return hits[i]; });
}

template <int N>
void IntersectOrigin(RTCScene scene, const Eigen::Vector3f& origin,
                     const std::vector<Eigen::Vector3f>& directions, RayHit* hits) {
  TracePackets<N>(
      scene, int64_t(directions.size()), std::numeric_limits<float>::infinity(), /*coherent=*/true,
      [&](int64_t i, Eigen::Vector3f* o, Eigen::Vector3f* direction) {
        *o = origin;
        *direction = directions[i];
      },
      [&](int64_t i) -> RayHit& { return hits[i]; });
}

// The pixels [u_begin, u_end) x [v_begin, v_end) of a camera whose rays can
// meet a box.
struct PixelWindow {
  int u_begin = 0, u_end = 0, v_begin = 0, v_end = 0;
};

// Every point of the box projects into the convex hull of its corners' images
// when all corners are in front of the camera, so a ray that hits inside the
// box passes through a pixel of their bounding rectangle; the rectangle is
// widened by kMargin pixels, far beyond the rounding of the rays' directions.
// A corner at or behind the camera plane gives the whole image; an empty box
// gives an empty window.
PixelWindow PixelsThatCanHit(const PinholeCamera& camera, const Eigen::Isometry3d& world_from_camera,
                             const Eigen::AlignedBox3d& box) {
  PixelWindow window;
  if (box.isEmpty()) return window;
  window.u_end = camera.width;
  window.v_end = camera.height;
  constexpr double kMargin = 2.0;
  const Eigen::Isometry3d camera_from_world = world_from_camera.inverse();
  double u_min = std::numeric_limits<double>::infinity(), u_max = -u_min;
  double v_min = u_min, v_max = -u_min;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p = camera_from_world * box.corner(Eigen::AlignedBox3d::CornerType(c));
    if (!(p.z() > 0.0)) return window;
    const double u = camera.fx * p.x() / p.z() + camera.cx, v = camera.fy * p.y() / p.z() + camera.cy;
    u_min = std::min(u_min, u), u_max = std::max(u_max, u);
    v_min = std::min(v_min, v), v_max = std::max(v_max, v);
  }
  const auto clamp = [](double x, int limit) { return int(std::clamp(x, 0.0, double(limit))); };
  window.u_begin = clamp(std::floor(u_min - kMargin), camera.width);
  window.u_end = clamp(std::ceil(u_max + kMargin) + 1.0, camera.width);
  window.v_begin = clamp(std::floor(v_min - kMargin), camera.height);
  window.v_end = clamp(std::ceil(v_max + kMargin) + 1.0, camera.height);
  return window;
}

// Emits the tile of rows [v0, v0 + kTileHeight) and columns [u0, u0 +
// kTileWidth) of a cast packet (see TraceCamera).
template <int N, typename Emit, typename RowEmit>
void EmitTile(const typename Packet<N>::Type& packet, const float* z_per_t, int v0, int u0, int row_begin,
              int row_end, int width, const Emit& emit, const RowEmit& row_emit) {
  constexpr int kTw = Packet<N>::kTileWidth, kTh = Packet<N>::kTileHeight;
  for (int dv = 0; dv < kTh && v0 + dv < row_end; ++dv) {
    const int64_t index = int64_t(v0 + dv - row_begin) * width + u0;
    // A whole tile row at once where the emitter can (row_emit returns true).
    if (u0 + kTw <= width && row_emit(index, packet, z_per_t, dv)) continue;
    for (int du = 0; du < kTw && u0 + du < width; ++du) {
      const int j = dv * kTw + du;
      emit(index + du, packet, j, z_per_t[j]);
    }
  }
}

// Casts one ray per pixel of rows [row_begin, row_end) in coherent tiles of
// Packet<N>::kTileWidth x kTileHeight pixels; lanes outside the image are masked
// off. The packet is filled in structure-of-arrays form, one SSE vector per
// tile row where the tile is 4 wide (the scalar per-pixel sqrt and division
// were a third of the scanner's time). After each packet, for every complete
// tile row, row_emit(index, packet, z_per_t, dv) may write the row at once and
// return true; otherwise (and for partial rows) emit(index, packet, lane,
// z_per_t) is called per pixel. index = (v - row_begin) * width + u (of the
// row's first pixel for row_emit); z_per_t is the camera z of the unit ray
// direction (depth = t * z_per_t). Tiles outside `window` are not cast: they
// are emitted as misses.
template <int N, typename Emit, typename RowEmit>
void TraceCamera(RTCScene scene, const PinholeCamera& camera,
                 const Eigen::Isometry3d& world_from_camera, int row_begin, int row_end,
                 const PixelWindow& window, const Emit& emit, const RowEmit& row_emit) {
  using P = Packet<N>;
  constexpr int kTw = P::kTileWidth, kTh = P::kTileHeight;
  const Eigen::Matrix3f r = world_from_camera.linear().cast<float>();
  const Eigen::Vector3f origin = world_from_camera.translation().cast<float>();
  const float inv_fx = float(1.0 / camera.fx), inv_fy = float(1.0 / camera.fy);
  const float cx = float(camera.cx), cy = float(camera.cy);
  const int width = camera.width;

  alignas(64) typename P::Type packet;
  alignas(64) int valid[N];
  alignas(64) float z_per_t[N];
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  // Embree reads but never writes these ray fields: set them once.
  for (int j = 0; j < N; ++j) {
    packet.ray.org_x[j] = origin.x();
    packet.ray.org_y[j] = origin.y();
    packet.ray.org_z[j] = origin.z();
    packet.ray.tnear[j] = 0.f;
    packet.ray.time[j] = 0.f;
    packet.ray.mask[j] = ~0u;
    packet.ray.id[j] = unsigned(j);
    packet.ray.flags[j] = 0;
    packet.hit.instID[0][j] = RTC_INVALID_GEOMETRY_ID;
    packet.ray.tfar[j] = std::numeric_limits<float>::infinity();  // read for skipped tiles
    z_per_t[j] = 1.f;
  }
  for (int v0 = row_begin; v0 < row_end; v0 += kTh) {
    const bool rows_can_hit = v0 < window.v_end && v0 + kTh > window.v_begin;
    for (int u0 = 0; u0 < width; u0 += kTw) {
      if (!rows_can_hit || u0 >= window.u_end || u0 + kTw <= window.u_begin) {
        for (int j = 0; j < N; ++j) packet.hit.geomID[j] = RTC_INVALID_GEOMETRY_ID;
        EmitTile<N>(packet, z_per_t, v0, u0, row_begin, row_end, width, emit, row_emit);
        continue;
      }
      const float x0 = (float(u0) - cx) * inv_fx, y0 = (float(v0) - cy) * inv_fy;
#if defined(__SSE2__)
      if constexpr (kTw == 4) {
        // One SSE vector per tile row, the same operations in the same order
        // as the scalar loop below (bit-identical rays).
        const __m128 one = _mm_set1_ps(1.f);
        const __m128 x = _mm_add_ps(_mm_set1_ps(x0), _mm_mul_ps(_mm_set_ps(3.f, 2.f, 1.f, 0.f),
                                                                 _mm_set1_ps(inv_fx)));
        const __m128 xx = _mm_mul_ps(x, x);
        const __m128 valid_u = _mm_castsi128_ps(
            _mm_cmplt_epi32(_mm_add_epi32(_mm_set1_epi32(u0), _mm_set_epi32(3, 2, 1, 0)),
                            _mm_set1_epi32(width)));
        for (int dv = 0; dv < kTh; ++dv) {
          const __m128 y = _mm_set1_ps(y0 + float(dv) * inv_fy);
          const __m128 inv_norm =
              _mm_div_ps(one, _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(xx, _mm_mul_ps(y, y)), one)));
          auto rotate = [&](int row) {
            return _mm_mul_ps(
                _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(r(row, 0)), x), _mm_mul_ps(_mm_set1_ps(r(row, 1)), y)),
                           _mm_set1_ps(r(row, 2))),
                inv_norm);
          };
          _mm_store_ps(&packet.ray.dir_x[4 * dv], rotate(0));
          _mm_store_ps(&packet.ray.dir_y[4 * dv], rotate(1));
          _mm_store_ps(&packet.ray.dir_z[4 * dv], rotate(2));
          _mm_store_ps(&packet.ray.tfar[4 * dv], _mm_set1_ps(std::numeric_limits<float>::infinity()));
          _mm_store_si128(reinterpret_cast<__m128i*>(&packet.hit.geomID[4 * dv]),
                          _mm_set1_epi32(int(RTC_INVALID_GEOMETRY_ID)));
          _mm_store_ps(&z_per_t[4 * dv], inv_norm);
          const __m128 valid_row = v0 + dv < row_end ? valid_u : _mm_setzero_ps();
          _mm_store_si128(reinterpret_cast<__m128i*>(&valid[4 * dv]), _mm_castps_si128(valid_row));
        }
      } else
#endif
      for (int j = 0; j < N; ++j) {
        const int du = j % kTw, dv = j / kTw;
        const float x = x0 + float(du) * inv_fx, y = y0 + float(dv) * inv_fy;
        const float inv_norm = 1.f / std::sqrt(x * x + y * y + 1.f);
        packet.ray.dir_x[j] = (r(0, 0) * x + r(0, 1) * y + r(0, 2)) * inv_norm;
        packet.ray.dir_y[j] = (r(1, 0) * x + r(1, 1) * y + r(1, 2)) * inv_norm;
        packet.ray.dir_z[j] = (r(2, 0) * x + r(2, 1) * y + r(2, 2)) * inv_norm;
        packet.ray.tfar[j] = std::numeric_limits<float>::infinity();
        packet.hit.geomID[j] = RTC_INVALID_GEOMETRY_ID;
        z_per_t[j] = inv_norm;
        valid[j] = (u0 + du < width && v0 + dv < row_end) ? -1 : 0;
      }
      P::Intersect(valid, scene, &context, &packet);
      EmitTile<N>(packet, z_per_t, v0, u0, row_begin, row_end, width, emit, row_emit);
    }
  }
}

template <int N>
void IntersectCameraHits(RTCScene scene, const PinholeCamera& camera,
                         const Eigen::Isometry3d& world_from_camera, int row_begin, int row_end,
                         const PixelWindow& window, RayHit* hits) {
  TraceCamera<N>(scene, camera, world_from_camera, row_begin, row_end, window,
                 [&](int64_t index, const typename Packet<N>::Type& packet, int j, float) {
                   RayHit& hit = hits[index];
                   if (packet.hit.geomID[j] == RTC_INVALID_GEOMETRY_ID) {
                     hit = RayHit();
                     return;
                   }
                   hit.t = packet.ray.tfar[j];
                   hit.geometry = int(packet.hit.geomID[j]);
                   hit.triangle = int(packet.hit.primID[j]);
                   hit.normal = FacingNormal(packet, j);
                 },
                 [](int64_t, const typename Packet<N>::Type&, const float*, int) { return false; });
}

template <int N>
void IntersectCameraBuffers(RTCScene scene, const PinholeCamera& camera,
                            const Eigen::Isometry3d& world_from_camera, int row_begin, int row_end,
                            const PixelWindow& window, const EmbreeScene::ImageOutputs& out) {
  TraceCamera<N>(
      scene, camera, world_from_camera, row_begin, row_end, window,
      [&](int64_t index, const typename Packet<N>::Type& packet, int j, float z_per_t) {
        const bool hit = packet.hit.geomID[j] != RTC_INVALID_GEOMETRY_ID;
        if (out.depth) {
          out.depth[index] = hit ? packet.ray.tfar[j] * z_per_t : std::numeric_limits<float>::infinity();
        }
        if (out.geometry) out.geometry[index] = hit ? int32_t(packet.hit.geomID[j]) : -1;
        if (out.triangle) out.triangle[index] = hit ? int32_t(packet.hit.primID[j]) : -1;
        if (out.normal) out.normal[index] = hit ? FacingNormal(packet, j) : Eigen::Vector3f::Zero();
      },
      [&](int64_t index, const typename Packet<N>::Type& packet, const float* z_per_t, int dv) {
#if defined(__SSE2__)
        // Depth and triangle only (the scanner's case), 4 pixels at once:
        // the same values as the per-lane path.
        if (Packet<N>::kTileWidth == 4 && out.geometry == nullptr && out.normal == nullptr) {
          const int j = 4 * dv;
          const __m128i miss = _mm_cmpeq_epi32(
              _mm_load_si128(reinterpret_cast<const __m128i*>(&packet.hit.geomID[j])),
              _mm_set1_epi32(int(RTC_INVALID_GEOMETRY_ID)));
          if (out.depth) {
            const __m128 depth = _mm_mul_ps(_mm_load_ps(&packet.ray.tfar[j]), _mm_load_ps(&z_per_t[j]));
            const __m128 miss_ps = _mm_castsi128_ps(miss);
            _mm_storeu_ps(out.depth + index,
                          _mm_or_ps(_mm_and_ps(miss_ps, _mm_set1_ps(std::numeric_limits<float>::infinity())),
                                    _mm_andnot_ps(miss_ps, depth)));
          }
          if (out.triangle) {
            const __m128i primitive = _mm_load_si128(reinterpret_cast<const __m128i*>(&packet.hit.primID[j]));
            _mm_storeu_si128(reinterpret_cast<__m128i*>(out.triangle + index),
                             _mm_or_si128(miss, _mm_andnot_si128(miss, primitive)));
          }
          return true;
        }
#endif
        (void)index, (void)packet, (void)z_per_t, (void)dv;
        return false;
      });
}

}  // namespace

void EmbreeScene::Intersect(const std::vector<Eigen::Vector3f>& origins,
                            const std::vector<Eigen::Vector3f>& directions,
                            std::vector<RayHit>* hits, float t_far) const {
  SAMP_CHECK(origins.size() == directions.size())
      << "EmbreeScene::Intersect: " << origins.size() << " origins but " << directions.size()
      << " directions";
  hits->resize(origins.size());
  switch (impl_->packet_size) {
    case 16: IntersectRays<16>(impl_->scene, origins, directions, t_far, hits->data()); break;
    case 8: IntersectRays<8>(impl_->scene, origins, directions, t_far, hits->data()); break;
    default: IntersectRays<4>(impl_->scene, origins, directions, t_far, hits->data()); break;
  }
  impl_->ThrowIfError("rtcIntersect");
}

void EmbreeScene::IntersectFromOrigin(const Eigen::Vector3f& origin,
                                      const std::vector<Eigen::Vector3f>& directions,
                                      std::vector<RayHit>* hits) const {
  hits->resize(directions.size());
  switch (impl_->packet_size) {
    case 16: IntersectOrigin<16>(impl_->scene, origin, directions, hits->data()); break;
    case 8: IntersectOrigin<8>(impl_->scene, origin, directions, hits->data()); break;
    default: IntersectOrigin<4>(impl_->scene, origin, directions, hits->data()); break;
  }
  impl_->ThrowIfError("rtcIntersect");
}

namespace {
void CheckCameraRows(const PinholeCamera& camera, int row_begin, int row_end) {
  SAMP_CHECK(camera.width > 0 && camera.height > 0 && camera.fx > 0 && camera.fy > 0)
      << "EmbreeScene: invalid camera " << camera.width << "x" << camera.height << ", fx "
      << camera.fx << ", fy " << camera.fy;
  SAMP_CHECK(0 <= row_begin && row_begin <= row_end && row_end <= camera.height)
      << "EmbreeScene: rows [" << row_begin << ", " << row_end << ") outside the image of height "
      << camera.height;
}
}  // namespace

void EmbreeScene::IntersectCamera(const PinholeCamera& camera,
                                  const Eigen::Isometry3d& world_from_camera, int row_begin,
                                  int row_end, RayHit* hits) const {
  CheckCameraRows(camera, row_begin, row_end);
  const PixelWindow window = PixelsThatCanHit(camera, world_from_camera, impl_->bounds);
  switch (impl_->packet_size) {
    case 16: IntersectCameraHits<16>(impl_->scene, camera, world_from_camera, row_begin, row_end, window, hits); break;
    case 8: IntersectCameraHits<8>(impl_->scene, camera, world_from_camera, row_begin, row_end, window, hits); break;
    default: IntersectCameraHits<4>(impl_->scene, camera, world_from_camera, row_begin, row_end, window, hits); break;
  }
  impl_->ThrowIfError("rtcIntersect");
}

void EmbreeScene::IntersectCameraImage(const PinholeCamera& camera,
                                       const Eigen::Isometry3d& world_from_camera, int row_begin,
                                       int row_end, const ImageOutputs& outputs) const {
  CheckCameraRows(camera, row_begin, row_end);
  const PixelWindow window = PixelsThatCanHit(camera, world_from_camera, impl_->bounds);
  switch (impl_->packet_size) {
    case 16: IntersectCameraBuffers<16>(impl_->scene, camera, world_from_camera, row_begin, row_end, window, outputs); break;
    case 8: IntersectCameraBuffers<8>(impl_->scene, camera, world_from_camera, row_begin, row_end, window, outputs); break;
    default: IntersectCameraBuffers<4>(impl_->scene, camera, world_from_camera, row_begin, row_end, window, outputs); break;
  }
  impl_->ThrowIfError("rtcIntersect");
}

}  // namespace samp
