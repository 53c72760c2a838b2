// The unsigned distance of ComputeSdf (sdf.cc, docs/sdf.md, "Value"):
//   a. exact narrow band: every seen triangle visits the voxels of its
//      bounding box grown by one voxel, rejects those whose distance to its
//      plane exceeds the band radius, and computes the exact closest point on
//      the triangle for the rest (keeping the nearest per voxel);
//   b. the rest of the grid by vector (closest-point) propagation: a forward
//      and a backward raster pass, each offering every voxel the closest
//      points of its 13 already-visited neighbours (Danielsson/Ragnemalm).
#include <algorithm>
#include <cmath>
#include <limits>

#include "libsamp/sdf/sdf_stages.h"

namespace samp {
namespace sdf_internal {
namespace {

// Closest point to p on triangle (a, b, c): Ericson, Real-Time Collision
// Detection, 5.1.5, with a fallback for degenerate triangles.
inline Vec3 ClosestOnSegment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const float len2 = ab.squaredNorm();
  if (len2 <= 0.0f) return a;
  const float t = std::clamp((p - a).dot(ab) / len2, 0.0f, 1.0f);
  return a + t * ab;
}

// Nearest of the three edges of a degenerate (zero-area) triangle.
Vec3 ClosestOnDegenerate(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 q0 = ClosestOnSegment(p, a, b), q1 = ClosestOnSegment(p, b, c), q2 = ClosestOnSegment(p, c, a);
  const float e0 = (p - q0).squaredNorm(), e1 = (p - q1).squaredNorm(), e2 = (p - q2).squaredNorm();
  return e0 <= e1 ? (e0 <= e2 ? q0 : q2) : (e1 <= e2 ? q1 : q2);
}

// u . v summed in the order of Eigen's dot of 3-vectors (x + (y + z)).
inline float Dot(float ux, float uy, float uz, float vx, float vy, float vz) {
  return ux * vx + (uy * vy + uz * vz);
}

// A triangle's corners and edges (ab = b - a, ac = c - a, bc = c - b) for
// ClosestOnTriangle.
struct TriangleEdges {
  Vec3 a, b, c, ab, ac, bc;
  explicit TriangleEdges(const Triangle& t) : a(t.a), b(t.b), c(t.c), ab(t.b - t.a), ac(t.c - t.a), bc(t.c - t.b) {}
};

// Closest point q to p on triangle (a, b, c): Ericson, Real-Time Collision
// Detection, 5.1.5: the Voronoi region of p (a corner, an edge or the face)
// from the dot products d1..d6 of the edges ab, ac with p - a, p - b, p - c
// and the barycentric numerators va, vb, vc; with a fallback for degenerate
// triangles. Scalar float operations, each in the same order as the
// Eigen-vector form of the same formulas.
inline void ClosestOnTriangle(const TriangleEdges& t, float px, float py, float pz, float* qx, float* qy,
                              float* qz) {
  const Vec3 &a = t.a, &b = t.b, &c = t.c, &ab = t.ab, &ac = t.ac;
  auto set = [&](float x, float y, float z) { *qx = x, *qy = y, *qz = z; };
  const float apx = px - a.x(), apy = py - a.y(), apz = pz - a.z();
  const float d1 = Dot(ab.x(), ab.y(), ab.z(), apx, apy, apz), d2 = Dot(ac.x(), ac.y(), ac.z(), apx, apy, apz);
  if (d1 <= 0.0f && d2 <= 0.0f) return set(a.x(), a.y(), a.z());
  const float bpx = px - b.x(), bpy = py - b.y(), bpz = pz - b.z();
  const float d3 = Dot(ab.x(), ab.y(), ab.z(), bpx, bpy, bpz), d4 = Dot(ac.x(), ac.y(), ac.z(), bpx, bpy, bpz);
  if (d3 >= 0.0f && d4 <= d3) return set(b.x(), b.y(), b.z());
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {  // edge ab
    const float denom = d1 - d3;
    if (!(denom > 0.0f)) return set(a.x(), a.y(), a.z());
    const float v = d1 / denom;
    return set(a.x() + v * ab.x(), a.y() + v * ab.y(), a.z() + v * ab.z());
  }
  const float cpx = px - c.x(), cpy = py - c.y(), cpz = pz - c.z();
  const float d5 = Dot(ab.x(), ab.y(), ab.z(), cpx, cpy, cpz), d6 = Dot(ac.x(), ac.y(), ac.z(), cpx, cpy, cpz);
  if (d6 >= 0.0f && d5 <= d6) return set(c.x(), c.y(), c.z());
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {  // edge ac
    const float denom = d2 - d6;
    if (!(denom > 0.0f)) return set(a.x(), a.y(), a.z());
    const float w = d2 / denom;
    return set(a.x() + w * ac.x(), a.y() + w * ac.y(), a.z() + w * ac.z());
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {  // edge bc
    const float denom = (d4 - d3) + (d5 - d6);
    if (!(denom > 0.0f)) return set(b.x(), b.y(), b.z());
    const float w = (d4 - d3) / denom;
    return set(b.x() + w * t.bc.x(), b.y() + w * t.bc.y(), b.z() + w * t.bc.z());
  }
  const float sum = va + vb + vc;
  if (!(sum > 0.0f)) {
    const Vec3 q = ClosestOnDegenerate(Vec3(px, py, pz), a, b, c);
    return set(q.x(), q.y(), q.z());
  }
  // Inside the face: q = a + ab v + ac w, v = vb / sum, w = vc / sum.
  const float denom = 1.0f / sum;
  const float v = vb * denom, w = vc * denom;
  set((a.x() + ab.x() * v) + ac.x() * w, (a.y() + ab.y() * v) + ac.y() * w, (a.z() + ab.z() * v) + ac.z() * w);
}

// |p - q|^2 summed in the order of Eigen's squaredNorm (x^2 + (y^2 + z^2)),
// so that every path gives bit-identical values.
inline float SquaredDistance(float dx, float dy, float dz) { return dx * dx + (dy * dy + dz * dz); }

// Offers voxels [i0, i1) of a row (x positions px, at y = py, z = pz) the
// closest points (qx, qy, qz)[i] with indices first + i; keeps the first
// strictly nearer one in best / source.
void OfferRow(const float* __restrict px, float py, float pz, const float* __restrict qx,
              const float* __restrict qy, const float* __restrict qz, int32_t first, int i0, int i1,
              float* __restrict best, int32_t* __restrict source) {
  for (int i = i0; i < i1; ++i) {
    const float d2 = SquaredDistance(px[i] - qx[i], py - qy[i], pz - qz[i]);
    const float b = best[i];
    const int32_t mask = -int32_t(d2 < b);
    best[i] = std::min(d2, b);  // d2 < b ? d2 : b
    source[i] = ((first + i) & mask) | (source[i] & ~mask);
  }
}

// Neighbour offsets (di, dj, dk) that precede a voxel in increasing index
// order; the first one is in the voxel's own row.
constexpr int kOffsets[13][3] = {{-1, 0, 0},  {-1, -1, 0}, {0, -1, 0},  {1, -1, 0},
                                 {-1, -1, -1}, {0, -1, -1}, {1, -1, -1}, {-1, 0, -1},
                                 {0, 0, -1},  {1, 0, -1},  {-1, 1, -1}, {0, 1, -1},
                                 {1, 1, -1}};

// One row of a propagation pass: voxels row + i, i in [0, nx), at x = px[i],
// y = py, z = pz; direction +1 (forward) or -1 (backward).
struct PassRow {
  int nx, direction;
  int64_t row;
  const float* px;
  float py, pz;
};

// The best of the closest points of the 12 neighbours in earlier rows (final
// for the row) for every voxel of the row (j, k) at once (vectorised):
// row_best[i] its squared distance, row_source[i] its voxel (-1: none).
void BestOfEarlierRows(const GridSpec& grid, const PassRow& r, int j, int k, const DistanceField& field,
                       float* row_best, int32_t* row_source) {
  const int nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  const int64_t sy = nx, sz = int64_t(nx) * ny;
  const float* cx = field.x.data();
  const float* cy = field.y.data();
  const float* cz = field.z.data();
  std::fill(row_best, row_best + nx, std::numeric_limits<float>::infinity());
  std::fill(row_source, row_source + nx, -1);
  for (int o = 1; o < 13; ++o) {
    const int di = r.direction * kOffsets[o][0], dj = r.direction * kOffsets[o][1],
              dk = r.direction * kOffsets[o][2];
    const int nj = j + dj, nk = k + dk;
    if (nj < 0 || nj >= ny || nk < 0 || nk >= nz) continue;
    const int64_t neighbour_row = sy * nj + sz * nk;
    OfferRow(r.px, r.py, r.pz, cx + neighbour_row + di, cy + neighbour_row + di,
             cz + neighbour_row + di, int32_t(neighbour_row + di), std::max(0, -di),
             nx - std::max(0, di), row_best, row_source);
  }
}

// Along the row: the voxel's own value, then the neighbour just before
// it, then the best of the earlier rows.
void SweepRow(const PassRow& r, const float* row_best, const int32_t* row_source, DistanceField* field) {
  float* squared = field->squared.data();
  float* cx = field->x.data();
  float* cy = field->y.data();
  float* cz = field->z.data();
  for (int ii = 0; ii < r.nx; ++ii) {
    const int i = r.direction > 0 ? ii : r.nx - 1 - ii;
    const int64_t v = r.row + i;
    float best = squared[v];
    int64_t best_n = -1;
    if (ii > 0) {
      const int64_t n = v - r.direction;
      const float dx = r.px[size_t(i)] - cx[n], dy = r.py - cy[n], dz = r.pz - cz[n];
      const float d2 = SquaredDistance(dx, dy, dz);
      if (d2 < best) {
        best = d2;
        best_n = n;
      }
    }
    if (row_best[size_t(i)] < best) {
      best = row_best[size_t(i)];
      best_n = row_source[size_t(i)];
    }
    if (best_n >= 0) {
      squared[v] = best;
      cx[v] = cx[best_n];
      cy[v] = cy[best_n];
      cz[v] = cz[best_n];
    }
  }
}

// Back along the row from the neighbour on the other side (as in
// Danielsson's 2-D passes), so that rows are not biased to one side.
void SweepRowBack(const PassRow& r, DistanceField* field) {
  float* squared = field->squared.data();
  float* cx = field->x.data();
  float* cy = field->y.data();
  float* cz = field->z.data();
  for (int ii = r.nx - 2; ii >= 0; --ii) {
    const int i = r.direction > 0 ? ii : r.nx - 1 - ii;
    const int64_t v = r.row + i;
    const int64_t n = v + r.direction;
    const float dx = r.px[size_t(i)] - cx[n], dy = r.py - cy[n], dz = r.pz - cz[n];
    const float d2 = SquaredDistance(dx, dy, dz);
    if (d2 < squared[v]) {
      squared[v] = d2;
      cx[v] = cx[n];
      cy[v] = cy[n];
      cz[v] = cz[n];
    }
  }
}

// One raster pass of closest-point propagation: forward (direction = +1)
// visits voxels in increasing index order and offers each the closest points
// of its 13 neighbours visited before it (the first strictly nearer one in
// kOffsets order wins); backward mirrors it. Row by row: the 12 neighbours in
// earlier rows are final for the row, so their best is found for the whole
// row at once (vectorised); then the sweep along the row adds the neighbour
// just before each voxel, which is offered first (as in a voxel-by-voxel
// sweep over kOffsets); then a sweep back along the row.
void PropagatePass(const GridSpec& grid, int direction, DistanceField* field) {
  const int nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  const float h = float(grid.voxel_size);
  const Vec3 origin = grid.origin.cast<float>();
  const int64_t sy = nx, sz = int64_t(nx) * ny;
  // Positions along a row and the best of the earlier rows per voxel.
  std::vector<float> px(static_cast<size_t>(nx));
  for (int i = 0; i < nx; ++i) px[size_t(i)] = origin.x() + h * float(i);
  std::vector<float> row_best(static_cast<size_t>(nx));
  std::vector<int32_t> row_source(static_cast<size_t>(nx));
  for (int kk = 0; kk < nz; ++kk) {
    const int k = direction > 0 ? kk : nz - 1 - kk;
    const float pz = origin.z() + h * float(k);
    for (int jj = 0; jj < ny; ++jj) {
      const int j = direction > 0 ? jj : ny - 1 - jj;
      const float py = origin.y() + h * float(j);
      const PassRow r{nx, direction, sy * j + sz * k, px.data(), py, pz};
      BestOfEarlierRows(grid, r, j, k, *field, row_best.data(), row_source.data());
      SweepRow(r, row_best.data(), row_source.data(), field);
      SweepRowBack(r, field);
    }
  }
}

}  // namespace

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
    const TriangleEdges edges(tri);
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
          const float px = row.x() + h * float(i);
          float qx, qy, qz;
          ClosestOnTriangle(edges, px, row.y(), row.z(), &qx, &qy, &qz);
          const float d2 = SquaredDistance(px - qx, row.y() - qy, row.z() - qz);
          if (d2 < field->squared[size_t(v)]) {
            field->squared[size_t(v)] = d2;
            field->x[size_t(v)] = qx;
            field->y[size_t(v)] = qy;
            field->z[size_t(v)] = qz;
          }
        }
      }
    }
  }
}

void PropagateDistances(const GridSpec& grid, DistanceField* field, std::vector<float>* distance) {
  PropagatePass(grid, +1, field);
  PropagatePass(grid, -1, field);
  PropagatePass(grid, +1, field);
  PropagatePass(grid, -1, field);
  const size_t num_voxels = size_t(grid.NumVoxels());
  distance->resize(num_voxels);
  for (size_t v = 0; v < num_voxels; ++v) (*distance)[v] = std::sqrt(field->squared[v]);
}

}  // namespace sdf_internal
}  // namespace samp
