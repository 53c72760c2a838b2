// Signed distance fields from scans (docs/sdf.md).
//
// 1. Unsigned distance to the triangles the scans saw:
//    a. exact narrow band: every seen triangle visits the voxels of its
//       bounding box grown by one voxel, rejects those whose distance to its
//       plane exceeds the band radius, and computes the exact closest point on
//       the triangle for the rest (keeping the nearest per voxel);
//    b. the rest of the grid by vector (closest-point) propagation: a forward
//       and a backward raster pass, each offering every voxel the closest
//       points of its 13 already-visited neighbours (Danielsson/Ragnemalm).
// 2. Sign by visibility carving: a voxel is outside if some view sees it in
//    front of the observed surface (or through empty space); near the surface
//    the pixel-centre depth is replaced by the plane of the triangle the pixel
//    saw, so the zero crossing does not depend on the pixel grid.
#include "libsamp/sdf/sdf.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "libsamp/core/error.h"

namespace samp {

void SdfOptions::Check() const {
  SAMP_CHECK(std::isfinite(truncation) && truncation >= 0.0)
      << "sdf: truncation must be >= 0 (0 = none), got " << truncation;
  SAMP_CHECK(std::isfinite(carve_margin) && carve_margin >= 0.0)
      << "sdf: carve_margin must be >= 0, got " << carve_margin;
  SAMP_CHECK(min_inside_fraction >= 0.0 && min_inside_fraction <= 1.0)
      << "sdf: min_inside_fraction must be in [0, 1], got " << min_inside_fraction;
}

std::string SdfSummary::BriefReport() const {
  std::ostringstream s;
  s << "SDF: " << num_seen_triangles << " seen triangles, inside fraction "
    << inside_fraction << (sign_ok ? "" : " (too small: sign failed)") << ", " << seconds
    << " s";
  return s.str();
}

namespace {

using Vec3 = Eigen::Vector3f;

// Closest point to p on triangle (a, b, c): Ericson, Real-Time Collision
// Detection, 5.1.5, with a fallback for degenerate triangles.
inline Vec3 ClosestOnSegment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const float len2 = ab.squaredNorm();
  if (len2 <= 0.0f) return a;
  const float t = std::clamp((p - a).dot(ab) / len2, 0.0f, 1.0f);
  return a + t * ab;
}

inline Vec3 ClosestOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return a;
  const Vec3 bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0f && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
    const float denom = d1 - d3;
    return denom > 0.0f ? Vec3(a + (d1 / denom) * ab) : a;
  }
  const Vec3 cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0f && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
    const float denom = d2 - d6;
    return denom > 0.0f ? Vec3(a + (d2 / denom) * ac) : a;
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
    const float denom = (d4 - d3) + (d5 - d6);
    return denom > 0.0f ? Vec3(b + ((d4 - d3) / denom) * (c - b)) : b;
  }
  const float sum = va + vb + vc;
  if (!(sum > 0.0f)) {
    // Degenerate (zero-area) triangle: nearest of its three edges.
    const Vec3 q0 = ClosestOnSegment(p, a, b), q1 = ClosestOnSegment(p, b, c),
               q2 = ClosestOnSegment(p, c, a);
    const float e0 = (p - q0).squaredNorm(), e1 = (p - q1).squaredNorm(),
                e2 = (p - q2).squaredNorm();
    return e0 <= e1 ? (e0 <= e2 ? q0 : q2) : (e1 <= e2 ? q1 : q2);
  }
  const float denom = 1.0f / sum;
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// A seen triangle, with its unit normal and plane offset (n . x = offset).
struct Triangle {
  Vec3 a, b, c;
  Vec3 normal;
  float offset;
};

// Far-away "closest point" of voxels not reached yet: its squared distance
// (~3e30) loses every comparison and stays finite in float.
constexpr float kFar = 1e15f;

struct DistanceField {
  std::vector<float> squared;   // squared distance per voxel
  std::vector<Vec3> closest;    // closest surface point per voxel
};

// Exact distances for the voxels with k in [k_begin, k_end) within `band` of
// the triangles in `triangles` (indices into `all`).
void SeedBand(const GridSpec& grid, const std::vector<Triangle>& all,
              const std::vector<int32_t>& triangles, float band, int k_begin, int k_end,
              DistanceField* field) {
  const float h = float(grid.voxel_size);
  const float inv_h = 1.0f / h;
  const Vec3 origin = grid.origin.cast<float>();
  const float band2 = band * band;
  const float band_voxels = band * inv_h;
  const int nx = grid.dims.x(), ny = grid.dims.y();
  for (const int32_t t : triangles) {
    const Triangle& tri = all[size_t(t)];
    const Vec3 lo = ((tri.a.cwiseMin(tri.b).cwiseMin(tri.c) - origin) * inv_h).array() - band_voxels;
    const Vec3 hi = ((tri.a.cwiseMax(tri.b).cwiseMax(tri.c) - origin) * inv_h).array() + band_voxels;
    const int i0 = std::max(0, int(std::ceil(lo.x()))), i1 = std::min(nx - 1, int(std::floor(hi.x())));
    const int j0 = std::max(0, int(std::ceil(lo.y()))), j1 = std::min(ny - 1, int(std::floor(hi.y())));
    const int k0 = std::max(k_begin, int(std::ceil(lo.z())));
    const int k1 = std::min(k_end - 1, int(std::floor(hi.z())));
    if (i0 > i1 || j0 > j1 || k0 > k1) continue;
    // Plane distance is linear in i along a row: s(i) = s0 + ds * i.
    const float ds = tri.normal.x() * h;
    for (int k = k0; k <= k1; ++k) {
      for (int j = j0; j <= j1; ++j) {
        const Vec3 row(origin.x(), origin.y() + h * float(j), origin.z() + h * float(k));
        const float s0 = tri.normal.dot(row) - tri.offset;
        int64_t v = grid.Index(i0, j, k);
        for (int i = i0; i <= i1; ++i, ++v) {
          const float s = s0 + ds * float(i);
          if (s * s > band2) continue;
          const Vec3 p(row.x() + h * float(i), row.y(), row.z());
          const Vec3 q = ClosestOnTriangle(p, tri.a, tri.b, tri.c);
          const float d2 = (p - q).squaredNorm();
          if (d2 < field->squared[size_t(v)]) {
            field->squared[size_t(v)] = d2;
            field->closest[size_t(v)] = q;
          }
        }
      }
    }
  }
}

// One raster pass of closest-point propagation: forward (direction = +1)
// visits voxels in increasing index order and offers each the closest points
// of its 13 neighbours visited before it; backward mirrors it.
void PropagatePass(const GridSpec& grid, int direction, DistanceField* field) {
  const int nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  const float h = float(grid.voxel_size);
  const Vec3 origin = grid.origin.cast<float>();
  // Neighbour offsets (di, dj, dk) that precede a voxel in increasing index order.
  static const int kOffsets[13][3] = {{-1, 0, 0},  {-1, -1, 0}, {0, -1, 0},  {1, -1, 0},
                                      {-1, -1, -1}, {0, -1, -1}, {1, -1, -1}, {-1, 0, -1},
                                      {0, 0, -1},  {1, 0, -1},  {-1, 1, -1}, {0, 1, -1},
                                      {1, 1, -1}};
  const int64_t sx = 1, sy = nx, sz = int64_t(nx) * ny;
  float* squared = field->squared.data();
  Vec3* closest = field->closest.data();
  for (int kk = 0; kk < nz; ++kk) {
    const int k = direction > 0 ? kk : nz - 1 - kk;
    for (int jj = 0; jj < ny; ++jj) {
      const int j = direction > 0 ? jj : ny - 1 - jj;
      const bool interior_jk = j > 0 && j < ny - 1 && k > 0 && k < nz - 1;
      for (int ii = 0; ii < nx; ++ii) {
        const int i = direction > 0 ? ii : nx - 1 - ii;
        const int64_t v = i + sy * j + sz * k;
        const Vec3 p(origin.x() + h * float(i), origin.y() + h * float(j), origin.z() + h * float(k));
        float best = squared[v];
        int64_t best_n = -1;
        const bool interior = interior_jk && i > 0 && i < nx - 1;
        for (const auto& o : kOffsets) {
          const int di = direction * o[0], dj = direction * o[1], dk = direction * o[2];
          if (!interior) {
            const int ni = i + di, nj = j + dj, nk = k + dk;
            if (ni < 0 || ni >= nx || nj < 0 || nj >= ny || nk < 0 || nk >= nz) continue;
          }
          const int64_t n = v + di * sx + dj * sy + dk * sz;
          const float d2 = (p - closest[n]).squaredNorm();
          if (d2 < best) {
            best = d2;
            best_n = n;
          }
        }
        if (best_n >= 0) {
          squared[v] = best;
          closest[v] = closest[best_n];
        }
      }
      // Back along the row from the neighbour on the other side (as in
      // Danielsson's 2-D passes), so that rows are not biased to one side.
      for (int ii = nx - 2; ii >= 0; --ii) {
        const int i = direction > 0 ? ii : nx - 1 - ii;
        const int64_t v = i + sy * j + sz * k;
        const int64_t n = v + direction;
        const Vec3 p(origin.x() + h * float(i), origin.y() + h * float(j), origin.z() + h * float(k));
        const float d2 = (p - closest[n]).squaredNorm();
        if (d2 < squared[v]) {
          squared[v] = d2;
          closest[v] = closest[n];
        }
      }
    }
  }
}

struct CarveView {
  Eigen::Matrix3f rotation;     // camera_from_object
  Vec3 translation;
  Vec3 camera_center;           // in the object frame
  float fx, fy, cx, cy;
  int width, height;
  float lateral_per_depth;      // half pixel diagonal per metre of depth (+10 %)
  const float* depth;
  const int32_t* triangle;
  // Every kCoarseStep-th pixel (from kCoarseOffset) along both axes: a small
  // image that stays in cache, used for voxels far enough from the surface.
  int coarse_width = 0, coarse_height = 0;
  std::vector<float> coarse_depth;
};

constexpr int kCoarseStep = 4;
constexpr int kCoarseOffset = (kCoarseStep - 1) / 2;

// Carves the voxels with k in [k_begin, k_end): sets outside[v] = 1 for the
// voxels some view sees in front of the surface, or that no view sees.
void CarveSlab(const GridSpec& grid, const std::vector<CarveView>& views,
               const std::vector<Triangle>& triangles, const std::vector<int32_t>& triangle_index,
               const std::vector<float>& distance, const SdfOptions& options, int k_begin,
               int k_end, std::vector<uint8_t>* outside) {
  const float h = float(grid.voxel_size);
  const Vec3 origin = grid.origin.cast<float>();
  const float margin = float(options.carve_margin);
  // Near the surface the pixel's triangle plane decides, unless the voxel is
  // this far behind the observed depth.
  const float behind_guard = h;
  const float on_plane = 1e-5f * h;
  const int nx = grid.dims.x(), ny = grid.dims.y();

  const size_t num_triangles = triangle_index.size();
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  constexpr int kTile = 8;
  // A voxel not carved yet.
  struct Active {
    Vec3 position;
    float distance;
    int32_t index;
    int32_t in_frustum;
  };
  std::vector<Active> active;
  active.reserve(kTile * kTile * kTile);
  // Tiles of 8^3 voxels: a tile projects onto a small patch of each depth
  // image, which keeps the lookups in cache. The inner loop is branch-free
  // except for the (rare) voxels near the surface.
  for (int tk = k_begin; tk < k_end; tk += kTile) {
    for (int tj = 0; tj < ny; tj += kTile) {
      for (int ti = 0; ti < nx; ti += kTile) {
        active.clear();
        for (int k = tk; k < std::min(k_end, tk + kTile); ++k) {
          for (int j = tj; j < std::min(ny, tj + kTile); ++j) {
            for (int i = ti; i < std::min(nx, ti + kTile); ++i) {
              const int64_t v = grid.Index(i, j, k);
              (*outside)[size_t(v)] = 1;  // until found uncarved below
              active.push_back({Vec3(origin.x() + h * float(i), origin.y() + h * float(j),
                                     origin.z() + h * float(k)),
                                distance[size_t(v)], int32_t(v), 0});
            }
          }
        }
        for (const CarveView& view : views) {
          size_t kept = 0;
          const float u_max = float(view.width) - 0.5f, w_max = float(view.height) - 0.5f;
          const float cu_max = float(view.coarse_width), cw_max = float(view.coarse_height);
          for (size_t a = 0; a < active.size(); ++a) {
            Active voxel = active[a];
            const Vec3 pc = view.rotation * voxel.position + view.translation;
            const float z = std::max(pc.z(), 1e-6f);
            const float inv_z = 1.0f / z;
            const float u = view.fx * pc.x() * inv_z + view.cx;
            const float w = view.fy * pc.y() * inv_z + view.cy;
            // Nearest pixel centre (centres at integer coordinates).
            const bool in_image =
                (pc.z() > 1e-6f) & (u >= -0.5f) & (w >= -0.5f) & (u < u_max) & (w < w_max);
            voxel.in_frustum |= int32_t(in_image);
            const float uc = std::clamp(u, 0.0f, u_max - 0.5f);
            const float wc = std::clamp(w, 0.0f, w_max - 0.5f);
            const int64_t pixel = int64_t(int(wc + 0.5f)) * view.width + int(uc + 0.5f);
            // The nearest coarse sample, within kCoarseStep / 2 pixels per axis.
            const float cu = (uc - float(kCoarseOffset)) * (1.0f / kCoarseStep) + 0.5f;
            const float cw = (wc - float(kCoarseOffset)) * (1.0f / kCoarseStep) + 0.5f;
            const float lateral = view.lateral_per_depth * z;
            const bool coarse = (voxel.distance > kCoarseStep * lateral) & (cu >= 0.0f) &
                                (cw >= 0.0f) & (cu < cu_max) & (cw < cw_max);
            const float* sample =
                coarse ? &view.coarse_depth[size_t(std::max(0, int(cw))) * size_t(view.coarse_width) +
                                            size_t(std::max(0, int(cu)))]
                       : &view.depth[pixel];
            const float observed = *sample;
            bool carved;
            if (voxel.distance > lateral) {
              // Far enough from the surface that the sampled ray and the
              // voxel's own ray cannot disagree about it (docs/sdf.md).
              carved = in_image & ((observed == kInfinity) | (z < observed - margin));
            } else {
              carved = false;
              if (in_image && observed < kInfinity && z < observed + behind_guard) {
                // Near the surface: in front of the plane of the triangle the
                // pixel saw, on the camera's side.
                const int32_t t = view.triangle[pixel];
                if (t >= 0 && size_t(t) < num_triangles && triangle_index[size_t(t)] >= 0) {
                  const Triangle& tri = triangles[size_t(triangle_index[size_t(t)])];
                  const float side_camera = tri.normal.dot(view.camera_center) - tri.offset;
                  const float side_voxel = tri.normal.dot(voxel.position) - tri.offset;
                  // A voxel on the plane (within rounding) counts as in
                  // front: it is on the surface, and must not be inside.
                  carved = side_camera > 0.0f   ? side_voxel > margin - on_plane
                           : side_camera < 0.0f ? side_voxel < on_plane - margin
                                                : false;
                }
              }
            }
            active[kept] = voxel;
            kept += size_t(!carved);
          }
          active.resize(kept);
          if (kept == 0) break;
        }
        // Uncarved voxels are inside, unless no view can see them.
        for (const Active& voxel : active) {
          (*outside)[size_t(voxel.index)] = voxel.in_frustum ? 0 : 1;
        }
      }
    }
  }
}

}  // namespace

Sdf ComputeSdf(const Mesh& mesh, const ScanResult& scan, const GridSpec& grid,
               const SdfOptions& options, bool parallel) {
  const auto start = std::chrono::steady_clock::now();
  options.Check();
  grid.Check();
  SAMP_CHECK(grid.NumVoxels() < std::numeric_limits<int32_t>::max())
      << "ComputeSdf: the grid has too many voxels (" << grid.NumVoxels() << ")";
  SAMP_CHECK(scan.triangle_seen.size() == mesh.triangles.size())
      << "ComputeSdf: the scan has " << scan.triangle_seen.size()
      << " triangle flags, the mesh has " << mesh.triangles.size() << " triangles";

  // Seen triangles, with planes. triangle_index maps mesh triangle -> seen index or -1.
  std::vector<Triangle> triangles;
  std::vector<int32_t> triangle_index(mesh.triangles.size(), -1);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (!scan.triangle_seen[t]) continue;
    const Eigen::Vector3i& f = mesh.triangles[t];
    for (int c = 0; c < 3; ++c) {
      SAMP_CHECK(f[c] >= 0 && size_t(f[c]) < mesh.vertices.size())
          << "ComputeSdf: triangle " << t << " has vertex index " << f[c] << " out of range";
    }
    Triangle tri;
    tri.a = mesh.vertices[size_t(f[0])];
    tri.b = mesh.vertices[size_t(f[1])];
    tri.c = mesh.vertices[size_t(f[2])];
    const Eigen::Vector3d n = (tri.b - tri.a).cast<double>().cross((tri.c - tri.a).cast<double>());
    const double norm = n.norm();
    tri.normal = norm > 0 ? Vec3((n / norm).cast<float>()) : Vec3::Zero();
    tri.offset = tri.normal.dot(tri.a);
    triangle_index[t] = int32_t(triangles.size());
    triangles.push_back(tri);
  }
  SAMP_CHECK(!triangles.empty()) << "ComputeSdf: the scans saw no triangle of the mesh";

  const int nz = grid.dims.z();
  const size_t num_voxels = size_t(grid.NumVoxels());
  // Slabs of z-slices, the unit of parallel work.
  const int slab = parallel ? 8 : nz;
  const int num_slabs = (nz + slab - 1) / slab;
  auto for_each_slab = [&](const auto& body) {
    if (parallel) {
      tbb::parallel_for(tbb::blocked_range<int>(0, num_slabs, 1), [&](const tbb::blocked_range<int>& r) {
        for (int s = r.begin(); s < r.end(); ++s) body(s * slab, std::min(nz, (s + 1) * slab));
      });
    } else {
      body(0, nz);
    }
  };

  // 1a. Exact narrow band.
  const float band = float(grid.voxel_size);
  DistanceField field;
  field.squared.assign(num_voxels, std::numeric_limits<float>::infinity());
  field.closest.assign(num_voxels, Vec3::Constant(kFar));
  std::vector<std::vector<int32_t>> slab_triangles(static_cast<size_t>(num_slabs));
  {
    const float inv_h = float(1.0 / grid.voxel_size);
    const float oz = float(grid.origin.z());
    const float band_voxels = band * inv_h;
    for (size_t t = 0; t < triangles.size(); ++t) {
      const Triangle& tri = triangles[t];
      const float zmin = std::min({tri.a.z(), tri.b.z(), tri.c.z()});
      const float zmax = std::max({tri.a.z(), tri.b.z(), tri.c.z()});
      const int k0 = std::max(0, int(std::ceil((zmin - oz) * inv_h - band_voxels)));
      const int k1 = std::min(nz - 1, int(std::floor((zmax - oz) * inv_h + band_voxels)));
      if (k0 > k1) continue;
      for (int s = k0 / slab; s <= k1 / slab; ++s) slab_triangles[size_t(s)].push_back(int32_t(t));
    }
  }
  for_each_slab([&](int k_begin, int k_end) {
    SeedBand(grid, triangles, slab_triangles[size_t(k_begin / slab)], band, k_begin, k_end, &field);
  });

  // 1b. Propagation to the whole grid (serial: each pass depends on the previous voxels).
  PropagatePass(grid, +1, &field);
  PropagatePass(grid, -1, &field);
  PropagatePass(grid, +1, &field);
  PropagatePass(grid, -1, &field);
  std::vector<float> distance(num_voxels);
  for (size_t v = 0; v < num_voxels; ++v) distance[v] = std::sqrt(field.squared[v]);
  field = DistanceField();

  // 2. Sign by visibility carving.
  std::vector<CarveView> views;
  views.reserve(scan.views.size());
  for (size_t index = 0; index < scan.views.size(); ++index) {
    const ScanView& view = scan.views[index];
    const int64_t pixels = int64_t(view.camera.width) * view.camera.height;
    SAMP_CHECK(int64_t(view.depth.size()) == pixels && int64_t(view.triangle.size()) == pixels)
        << "ComputeSdf: scan view " << index << " has " << view.depth.size() << " depths and "
        << view.triangle.size() << " triangle ids for " << pixels << " pixels";
    CarveView carve;
    carve.rotation = view.camera_from_object.linear().cast<float>();
    carve.translation = view.camera_from_object.translation().cast<float>();
    carve.camera_center = view.camera_from_object.inverse().translation().cast<float>();
    carve.fx = float(view.camera.fx);
    carve.fy = float(view.camera.fy);
    carve.cx = float(view.camera.cx);
    carve.cy = float(view.camera.cy);
    carve.width = view.camera.width;
    carve.height = view.camera.height;
    // Slightly more than half the pixel diagonal.
    carve.lateral_per_depth = float(
        0.55 * std::sqrt(1.0 / (view.camera.fx * view.camera.fx) + 1.0 / (view.camera.fy * view.camera.fy)));
    carve.depth = view.depth.data();
    carve.triangle = view.triangle.data();
    carve.coarse_width = std::max(0, (carve.width - 1 - kCoarseOffset) / kCoarseStep + 1);
    carve.coarse_height = std::max(0, (carve.height - 1 - kCoarseOffset) / kCoarseStep + 1);
    carve.coarse_depth.resize(size_t(carve.coarse_width) * size_t(carve.coarse_height));
    for (int cw = 0; cw < carve.coarse_height; ++cw) {
      const float* row = carve.depth + int64_t(kCoarseOffset + cw * kCoarseStep) * carve.width;
      for (int cu = 0; cu < carve.coarse_width; ++cu) {
        carve.coarse_depth[size_t(cw) * size_t(carve.coarse_width) + size_t(cu)] =
            row[kCoarseOffset + cu * kCoarseStep];
      }
    }
    views.push_back(carve);
  }
  std::vector<uint8_t> outside(num_voxels, 0);
  for_each_slab([&](int k_begin, int k_end) {
    CarveSlab(grid, views, triangles, triangle_index, distance, options, k_begin, k_end, &outside);
  });

  Sdf sdf;
  sdf.grid = grid;
  sdf.values.resize(num_voxels);
  const float truncation = float(options.truncation);
  int64_t inside = 0;
  for (size_t v = 0; v < num_voxels; ++v) {
    float value = outside[v] ? distance[v] : -distance[v];
    if (!outside[v]) ++inside;
    if (truncation > 0.0f) value = std::clamp(value, -truncation, truncation);
    sdf.values[v] = value;
  }
  sdf.summary.num_seen_triangles = int(triangles.size());
  sdf.summary.inside_fraction = double(inside) / double(num_voxels);
  sdf.summary.sign_ok = sdf.summary.inside_fraction >= options.min_inside_fraction;
  sdf.summary.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return sdf;
}

}  // namespace samp
