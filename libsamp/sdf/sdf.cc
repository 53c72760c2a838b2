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
#include <cstdio>
#include <sstream>

#include "libsamp/core/error.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace samp {

void SdfOptions::Check() const {
  SAMP_CHECK(std::isfinite(truncation) && truncation >= 0.0)
      << "sdf: truncation must be >= 0 (0 = none), got " << truncation;
  SAMP_CHECK(std::isfinite(carve_margin) && carve_margin >= 0.0)
      << "sdf: carve_margin must be >= 0, got " << carve_margin;
  SAMP_CHECK(min_inside_fraction >= 0.0 && min_inside_fraction <= 1.0)
      << "sdf: min_inside_fraction must be in [0, 1], got " << min_inside_fraction;
  SAMP_CHECK(sign == Sign::kCarving || sign == Sign::kCarvingAndClosing)
      << "sdf: sign must be kCarving or kCarvingAndClosing";
  SAMP_CHECK(std::isfinite(closing_radius_voxels) && closing_radius_voxels > 0.0 &&
             closing_radius_voxels <= 16.0)
      << "sdf: closing_radius_voxels must be in (0, 16], got " << closing_radius_voxels;
}

void SdfQualityOptions::Check() const {
  auto in_unit = [](double v) { return std::isfinite(v) && v >= 0.0 && v <= 1.0; };
  SAMP_CHECK(in_unit(min_box_fill) && in_unit(borderline_box_fill) && min_box_fill <= borderline_box_fill)
      << "sdf gate: need 0 <= min_box_fill <= borderline_box_fill <= 1, got " << min_box_fill << ", "
      << borderline_box_fill;
  SAMP_CHECK(in_unit(min_largest_component) && in_unit(borderline_largest_component) &&
             min_largest_component <= borderline_largest_component)
      << "sdf gate: need 0 <= min_largest_component <= borderline_largest_component <= 1, got "
      << min_largest_component << ", " << borderline_largest_component;
  SAMP_CHECK(in_unit(min_closing_agreement) && in_unit(borderline_closing_agreement) &&
             min_closing_agreement <= borderline_closing_agreement)
      << "sdf gate: need 0 <= min_closing_agreement <= borderline_closing_agreement <= 1, got "
      << min_closing_agreement << ", " << borderline_closing_agreement;
}

SdfQuality CheckSdfQuality(const Sdf& sdf, const AlignedBox& shape_box, const SdfQualityOptions& options) {
  options.Check();
  SdfQuality q;
  const GridSpec& grid = sdf.grid;
  // The shape's box within the grid's box (voxel centres +- h / 2).
  const Eigen::Vector3d half(0.5 * grid.voxel_size, 0.5 * grid.voxel_size, 0.5 * grid.voxel_size);
  const Eigen::Vector3d lo = shape_box.min.cwiseMax(grid.MinCorner() - half);
  const Eigen::Vector3d hi = shape_box.max.cwiseMin(grid.MaxCorner() + half);
  const double box_volume = (hi - lo).cwiseMax(0.0).prod();
  const double inside_volume =
      sdf.summary.inside_fraction * double(grid.NumVoxels()) * std::pow(grid.voxel_size, 3);
  q.box_fill = box_volume > 0.0 ? inside_volume / box_volume : 0.0;
  q.largest_component = sdf.summary.largest_component_share;
  q.closing_agreement = sdf.summary.inside_fraction > 0.0
                            ? std::min(1.0, sdf.summary.closing_inside_fraction / sdf.summary.inside_fraction)
                            : 0.0;
  std::ostringstream failed, borderline;
  auto check = [&](const char* name, double value, double minimum, double limit) {
    char text[160];
    if (value < minimum) {
      std::snprintf(text, sizeof(text), "%s%s %.3f below the minimum %.3f", failed.tellp() > 0 ? "; " : "", name,
                    value, minimum);
      failed << text;
    } else if (value < limit) {
      std::snprintf(text, sizeof(text), "%s%s %.3f below %.3f", borderline.tellp() > 0 ? "; " : "", name, value,
                    limit);
      borderline << text;
    }
  };
  check("inside volume / box volume", q.box_fill, options.min_box_fill, options.borderline_box_fill);
  check("largest inside component share", q.largest_component, options.min_largest_component,
        options.borderline_largest_component);
  check("closing agreement", q.closing_agreement, options.min_closing_agreement,
        options.borderline_closing_agreement);
  q.pass = failed.tellp() == 0;
  q.borderline = q.pass && borderline.tellp() > 0;
  q.reason = q.pass ? borderline.str() : failed.str();
  return q;
}

std::string SdfSummary::BriefReport() const {
  std::ostringstream s;
  s << "SDF: " << num_seen_triangles << " seen triangles, inside fraction "
    << inside_fraction << (sign_ok ? "" : " (too small: sign failed)")
    << " (carving " << carving_inside_fraction << ", closing " << closing_inside_fraction
    << ", disagreement " << sign_disagreement << "), largest inside component "
    << largest_component_share << " of " << num_inside_components << ", " << seconds << " s";
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

// Squared distance and closest surface point (x, y, z) per voxel.
struct DistanceField {
  std::vector<float> squared;
  std::vector<float> x, y, z;
};

// |p - q|^2 summed in the order of Eigen's squaredNorm (x^2 + (y^2 + z^2)),
// so that every path gives bit-identical values.
inline float SquaredDistance(float dx, float dy, float dz) { return dx * dx + (dy * dy + dz * dz); }

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
            field->x[size_t(v)] = q.x();
            field->y[size_t(v)] = q.y();
            field->z[size_t(v)] = q.z();
          }
        }
      }
    }
  }
}

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
  // Neighbour offsets (di, dj, dk) that precede a voxel in increasing index
  // order; the first one is in the voxel's own row.
  static const int kOffsets[13][3] = {{-1, 0, 0},  {-1, -1, 0}, {0, -1, 0},  {1, -1, 0},
                                      {-1, -1, -1}, {0, -1, -1}, {1, -1, -1}, {-1, 0, -1},
                                      {0, 0, -1},  {1, 0, -1},  {-1, 1, -1}, {0, 1, -1},
                                      {1, 1, -1}};
  const int64_t sy = nx, sz = int64_t(nx) * ny;
  float* squared = field->squared.data();
  float* cx = field->x.data();
  float* cy = field->y.data();
  float* cz = field->z.data();
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
      const int64_t row = sy * j + sz * k;
      std::fill(row_best.begin(), row_best.end(), std::numeric_limits<float>::infinity());
      std::fill(row_source.begin(), row_source.end(), -1);
      for (int o = 1; o < 13; ++o) {
        const int di = direction * kOffsets[o][0], dj = direction * kOffsets[o][1],
                  dk = direction * kOffsets[o][2];
        const int nj = j + dj, nk = k + dk;
        if (nj < 0 || nj >= ny || nk < 0 || nk >= nz) continue;
        const int64_t neighbour_row = sy * nj + sz * nk;
        OfferRow(px.data(), py, pz, cx + neighbour_row + di, cy + neighbour_row + di,
                 cz + neighbour_row + di, int32_t(neighbour_row + di), std::max(0, -di),
                 nx - std::max(0, di), row_best.data(), row_source.data());
      }
      // Along the row: the voxel's own value, then the neighbour just before
      // it, then the best of the earlier rows.
      for (int ii = 0; ii < nx; ++ii) {
        const int i = direction > 0 ? ii : nx - 1 - ii;
        const int64_t v = row + i;
        float best = squared[v];
        int64_t best_n = -1;
        if (ii > 0) {
          const int64_t n = v - direction;
          const float dx = px[size_t(i)] - cx[n], dy = py - cy[n], dz = pz - cz[n];
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
      // Back along the row from the neighbour on the other side (as in
      // Danielsson's 2-D passes), so that rows are not biased to one side.
      for (int ii = nx - 2; ii >= 0; --ii) {
        const int i = direction > 0 ? ii : nx - 1 - ii;
        const int64_t v = row + i;
        const int64_t n = v + direction;
        const float dx = px[size_t(i)] - cx[n], dy = py - cy[n], dz = pz - cz[n];
        const float d2 = SquaredDistance(dx, dy, dz);
        if (d2 < squared[v]) {
          squared[v] = d2;
          cx[v] = cx[n];
          cy[v] = cy[n];
          cz[v] = cz[n];
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
  // Minimum and maximum depth (inf included) over cells of kCell x kCell
  // pixels: a block of voxels whose pixels lie in a few cells is decided at once.
  int cell_width = 0, cell_height = 0;
  std::vector<float> cell_min, cell_max;
};

constexpr int kCoarseStep = 4;
constexpr int kCoarseOffset = (kCoarseStep - 1) / 2;
constexpr int kCell = 8;

// Fills the coarse image and the min/max depth over cells of kCell x kCell
// pixels, in one pass over the depth image.
void BuildViewTables(CarveView* view) {
  const int width = view->width, height = view->height;
  view->coarse_width = std::max(0, (width - 1 - kCoarseOffset) / kCoarseStep + 1);
  view->coarse_height = std::max(0, (height - 1 - kCoarseOffset) / kCoarseStep + 1);
  view->coarse_depth.resize(size_t(view->coarse_width) * size_t(view->coarse_height));
  view->cell_width = (width + kCell - 1) / kCell;
  view->cell_height = (height + kCell - 1) / kCell;
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  view->cell_min.assign(size_t(view->cell_width) * size_t(view->cell_height), kInfinity);
  view->cell_max.assign(size_t(view->cell_width) * size_t(view->cell_height), -kInfinity);
  // Column-wise min/max over the rows of one cell row, then over the columns of each cell.
  std::vector<float> column_min(static_cast<size_t>(width)), column_max(static_cast<size_t>(width));
  for (int cw = 0; cw < view->cell_height; ++cw) {
    const int v0 = cw * kCell, v1 = std::min(height, v0 + kCell);
    std::fill(column_min.begin(), column_min.end(), kInfinity);
    std::fill(column_max.begin(), column_max.end(), -kInfinity);
    for (int v = v0; v < v1; ++v) {
      const float* row = view->depth + int64_t(v) * width;
      float* lo = column_min.data();
      float* hi = column_max.data();
      for (int u = 0; u < width; ++u) {
        lo[u] = std::min(lo[u], row[u]);
        hi[u] = std::max(hi[u], row[u]);
      }
      if (v >= kCoarseOffset && (v - kCoarseOffset) % kCoarseStep == 0) {
        float* coarse = &view->coarse_depth[size_t((v - kCoarseOffset) / kCoarseStep) *
                                            size_t(view->coarse_width)];
        for (int cu = 0; cu < view->coarse_width; ++cu) coarse[cu] = row[kCoarseOffset + cu * kCoarseStep];
      }
    }
    float* out_min = &view->cell_min[size_t(cw) * size_t(view->cell_width)];
    float* out_max = &view->cell_max[size_t(cw) * size_t(view->cell_width)];
    for (int u = 0; u < width; ++u) {
      const int cu = u / kCell;
      out_min[cu] = std::min(out_min[cu], column_min[size_t(u)]);
      out_max[cu] = std::max(out_max[cu], column_max[size_t(u)]);
    }
  }
}

// A voxel not carved yet.
struct Active {
  Vec3 position;
  float distance;
  int32_t index;
  uint8_t in_frustum;  // some view had it in its image
  uint8_t cell;        // its 2^3 cell within its block (voxels of a cell are contiguous)
};

// A set of voxels (a block, a cell, or the near voxels of a block): a
// segment [begin, begin + count) of the active list.
struct Block {
  int begin = 0, count = 0;
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  // bounding box of the active voxel centres
  float min_distance = 0.f;  // smallest distance of the active voxels
  bool seen = false;         // some view had all of them in its image
  bool per_voxel = false;    // voxels near the surface: always tested one by one
  bool stale = true;         // (cells) lo, hi, min_distance to be recomputed
};

enum class BlockDecision { kUndecided, kOutOfView, kNoneCarved, kAllCarved };

// Decides a set of far voxels for one view when the per-voxel rule must give
// the same answer for each of them: every voxel samples a pixel within
// kSampleSlack pixels of its projection (nearest pixel or coarse sample), and
// the projections of the points of the bounding sphere of the set lie within
// the bounds used here. Tolerances keep the decision on the safe side of float
// rounding; whatever is not clear-cut is left to the per-voxel test.
BlockDecision DecideBlock(const CarveView& view, const Block& block, float margin) {
  constexpr float kDepthEps = 1e-4f;    // metres
  constexpr float kPixelEps = 1e-2f;    // pixels
  constexpr float kSampleSlack = 3.0f;  // pixels (the coarse sample is within 2)
  const Vec3 centre = 0.5f * (block.lo + block.hi);
  const float radius = 0.5f * (block.hi - block.lo).norm() * 1.0001f + 1e-6f;
  const Vec3 pc = view.rotation * centre + view.translation;
  const float zmin = pc.z() - radius - kDepthEps, zmax = pc.z() + radius + kDepthEps;
  if (!(zmin > 1e-3f)) return BlockDecision::kUndecided;
  // Every voxel far from the surface (the plane test of near voxels is per voxel).
  if (!(block.min_distance > view.lateral_per_depth * zmax)) return BlockDecision::kUndecided;
  // For p = centre + d, |d| <= radius: |x/z - xc/zc| <= radius * |(zc, xc)| / (zc * zmin).
  const float inv_z = 1.0f / pc.z();
  const float u = view.fx * pc.x() * inv_z + view.cx;
  const float w = view.fy * pc.y() * inv_z + view.cy;
  const float spread = radius * inv_z / zmin;
  const float du = view.fx * spread * std::sqrt(pc.z() * pc.z() + pc.x() * pc.x()) + kPixelEps;
  const float dw = view.fy * spread * std::sqrt(pc.z() * pc.z() + pc.y() * pc.y()) + kPixelEps;
  const float u_max = float(view.width) - 0.5f, w_max = float(view.height) - 0.5f;
  // No voxel in the image: none carved, and none gets into the frustum.
  if (u + du < -0.5f || w + dw < -0.5f || u - du >= u_max || w - dw >= w_max) {
    return BlockDecision::kOutOfView;
  }
  const bool all_in_image = u - du >= -0.5f && w - dw >= -0.5f && u + du < u_max && w + dw < w_max;
  // Partly in the image: which voxels enter the frustum is per voxel.
  if (!all_in_image && !block.seen) return BlockDecision::kUndecided;
  const float last_u = float(view.width - 1), last_w = float(view.height - 1);
  float lowest = std::numeric_limits<float>::infinity(), highest = 0.0f;
  // Voxels far enough to use the coarse image sample it at exactly these
  // indices (as in VoxelCarver::Project, from the clamped projection).
  constexpr float kIndexEps = 1e-3f;
  const float ua = std::clamp(u - du, 0.0f, last_u), ub = std::clamp(u + du, 0.0f, last_u);
  const float wa = std::clamp(w - dw, 0.0f, last_w), wb = std::clamp(w + dw, 0.0f, last_w);
  const float cua = (ua - float(kCoarseOffset)) * (1.0f / kCoarseStep) + 0.5f - kIndexEps;
  const float cub = (ub - float(kCoarseOffset)) * (1.0f / kCoarseStep) + 0.5f + kIndexEps;
  const float cwa = (wa - float(kCoarseOffset)) * (1.0f / kCoarseStep) + 0.5f - kIndexEps;
  const float cwb = (wb - float(kCoarseOffset)) * (1.0f / kCoarseStep) + 0.5f + kIndexEps;
  if (block.min_distance > kCoarseStep * view.lateral_per_depth * zmax &&
      cub < float(view.coarse_width) && cwb < float(view.coarse_height)) {
    const int cu0 = std::max(0, int(cua)), cu1 = int(cub);
    const int cw0 = std::max(0, int(cwa)), cw1 = int(cwb);
    for (int cw = cw0; cw <= cw1; ++cw) {
      const float* row = &view.coarse_depth[size_t(cw) * size_t(view.coarse_width)];
      for (int cu = cu0; cu <= cu1; ++cu) {
        lowest = std::min(lowest, row[cu]);
        highest = std::max(highest, row[cu]);
      }
    }
  } else {
    // Otherwise a pixel within kSampleSlack of the projection: the min/max cells.
    const int cu0 = int(std::clamp(u - du - kSampleSlack, 0.0f, last_u)) / kCell;
    const int cu1 = int(std::clamp(u + du + kSampleSlack, 0.0f, last_u)) / kCell;
    const int cw0 = int(std::clamp(w - dw - kSampleSlack, 0.0f, last_w)) / kCell;
    const int cw1 = int(std::clamp(w + dw + kSampleSlack, 0.0f, last_w)) / kCell;
    for (int cw = cw0; cw <= cw1; ++cw) {
      const size_t row = size_t(cw) * size_t(view.cell_width);
      for (int cu = cu0; cu <= cu1; ++cu) {
        lowest = std::min(lowest, view.cell_min[row + size_t(cu)]);
        highest = std::max(highest, view.cell_max[row + size_t(cu)]);
      }
    }
  }
  // Not carved (and all in the image, or seen before): every sampled depth
  // is finite and at most margin in front of the voxel.
  if (highest <= zmin + margin) return BlockDecision::kNoneCarved;
  // Carved: every voxel in the image and in front of every sampled depth (or a miss).
  if (all_in_image && lowest - margin > zmax) return BlockDecision::kAllCarved;
  return BlockDecision::kUndecided;
}

// The per-voxel carving rule of one view (docs/sdf.md), in two steps so that
// the depth (and triangle) loads of a run of voxels are in flight together:
// Probe projects a voxel, records whether it is in the view's image, and
// prefetches what Carved will read.
class VoxelCarver {
 public:
  struct Probe {
    const float* sample;  // the depth sample that decides a far voxel
    int32_t pixel;        // nearest pixel
    float z;              // camera depth
    bool in_image;
    bool near;            // within the lateral tolerance of the surface
  };

  VoxelCarver(const CarveView& view, const std::vector<Triangle>& triangles,
              const std::vector<int32_t>& triangle_index, float voxel_size, float margin)
      : view_(view),
        triangles_(triangles),
        triangle_index_(triangle_index),
        margin_(margin),
        behind_guard_(voxel_size),
        on_plane_(1e-5f * voxel_size),
        u_max_(float(view.width) - 0.5f),
        w_max_(float(view.height) - 0.5f),
        cu_max_(float(view.coarse_width)),
        cw_max_(float(view.coarse_height)) {}

  Probe Project(Active* voxel) const {
    const CarveView& view = view_;
    const Eigen::Matrix3f& r = view.rotation;
    const Vec3& q = voxel->position;
    const Vec3 pc((r(0, 0) * q.x() + r(0, 1) * q.y() + r(0, 2) * q.z()) + view.translation.x(),
                  (r(1, 0) * q.x() + r(1, 1) * q.y() + r(1, 2) * q.z()) + view.translation.y(),
                  (r(2, 0) * q.x() + r(2, 1) * q.y() + r(2, 2) * q.z()) + view.translation.z());
    Probe probe;
    probe.z = std::max(pc.z(), 1e-6f);
    const float inv_z = 1.0f / probe.z;
    const float u = view.fx * pc.x() * inv_z + view.cx;
    const float w = view.fy * pc.y() * inv_z + view.cy;
    // Nearest pixel centre (centres at integer coordinates).
    probe.in_image = (pc.z() > 1e-6f) & (u >= -0.5f) & (w >= -0.5f) & (u < u_max_) & (w < w_max_);
    voxel->in_frustum |= uint8_t(probe.in_image);
    const float uc = std::clamp(u, 0.0f, u_max_ - 0.5f);
    const float wc = std::clamp(w, 0.0f, w_max_ - 0.5f);
    probe.pixel = int(wc + 0.5f) * view.width + int(uc + 0.5f);
    // The nearest coarse sample, within kCoarseStep / 2 pixels per axis.
    const float cu = (uc - float(kCoarseOffset)) * (1.0f / kCoarseStep) + 0.5f;
    const float cw = (wc - float(kCoarseOffset)) * (1.0f / kCoarseStep) + 0.5f;
    const float lateral = view.lateral_per_depth * probe.z;
    const bool coarse = (voxel->distance > kCoarseStep * lateral) & (cu >= 0.0f) & (cw >= 0.0f) &
                        (cu < cu_max_) & (cw < cw_max_);
    probe.sample =
        coarse ? &view.coarse_depth[size_t(std::max(0, int(cw))) * size_t(view.coarse_width) +
                                    size_t(std::max(0, int(cu)))]
               : &view.depth[probe.pixel];
    probe.near = !(voxel->distance > lateral);
    __builtin_prefetch(probe.sample);
    if (probe.near) __builtin_prefetch(&view.triangle[probe.pixel]);
    return probe;
  }

  bool Carved(const Active& voxel, const Probe& probe) const {
    constexpr float kInfinity = std::numeric_limits<float>::infinity();
    const float observed = *probe.sample;
    if (!probe.near) {
      // Far enough from the surface that the sampled ray and the voxel's own
      // ray cannot disagree about it (docs/sdf.md).
      return probe.in_image & ((observed == kInfinity) | (probe.z < observed - margin_));
    }
    if (!(probe.in_image && observed < kInfinity && probe.z < observed + behind_guard_)) {
      return false;
    }
    // Near the surface: in front of the plane of the triangle the pixel saw,
    // on the camera's side.
    const int32_t t = view_.triangle[probe.pixel];
    if (t < 0 || size_t(t) >= triangle_index_.size() || triangle_index_[size_t(t)] < 0) return false;
    const Triangle& tri = triangles_[size_t(triangle_index_[size_t(t)])];
    const float side_camera = tri.normal.dot(view_.camera_center) - tri.offset;
    const float side_voxel = tri.normal.dot(voxel.position) - tri.offset;
    // A voxel on the plane (within rounding) counts as in front: it is on the
    // surface, and must not be inside.
    return side_camera > 0.0f   ? side_voxel > margin_ - on_plane_
           : side_camera < 0.0f ? side_voxel < on_plane_ - margin_
                                : false;
  }

#if defined(__SSE2__)
  // Project for voxels[which[0..4)], four at a time: the same operations in
  // the same order (bit-identical probes).
  void Project4(Active* voxels, const int* which, Probe* probes) const {
    const CarveView& view = view_;
    Active* v[4] = {&voxels[which[0]], &voxels[which[1]], &voxels[which[2]], &voxels[which[3]]};
    const __m128 qx = _mm_setr_ps(v[0]->position.x(), v[1]->position.x(), v[2]->position.x(), v[3]->position.x());
    const __m128 qy = _mm_setr_ps(v[0]->position.y(), v[1]->position.y(), v[2]->position.y(), v[3]->position.y());
    const __m128 qz = _mm_setr_ps(v[0]->position.z(), v[1]->position.z(), v[2]->position.z(), v[3]->position.z());
    const __m128 distance = _mm_setr_ps(v[0]->distance, v[1]->distance, v[2]->distance, v[3]->distance);
    const Eigen::Matrix3f& r = view.rotation;
    auto row = [&](int i) {
      return _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(r(i, 0)), qx),
                                              _mm_mul_ps(_mm_set1_ps(r(i, 1)), qy)),
                                   _mm_mul_ps(_mm_set1_ps(r(i, 2)), qz)),
                        _mm_set1_ps(view.translation[i]));
    };
    const __m128 pcx = row(0), pcy = row(1), pcz = row(2);
    const __m128 tiny = _mm_set1_ps(1e-6f);
    const __m128 z = _mm_max_ps(pcz, tiny);
    const __m128 inv_z = _mm_div_ps(_mm_set1_ps(1.0f), z);
    const __m128 u = _mm_add_ps(_mm_mul_ps(_mm_mul_ps(_mm_set1_ps(view.fx), pcx), inv_z), _mm_set1_ps(view.cx));
    const __m128 w = _mm_add_ps(_mm_mul_ps(_mm_mul_ps(_mm_set1_ps(view.fy), pcy), inv_z), _mm_set1_ps(view.cy));
    const __m128 minus_half = _mm_set1_ps(-0.5f);
    const __m128 in_image = _mm_and_ps(
        _mm_and_ps(_mm_cmpgt_ps(pcz, tiny), _mm_and_ps(_mm_cmpge_ps(u, minus_half), _mm_cmpge_ps(w, minus_half))),
        _mm_and_ps(_mm_cmplt_ps(u, _mm_set1_ps(u_max_)), _mm_cmplt_ps(w, _mm_set1_ps(w_max_))));
    const __m128 zero = _mm_setzero_ps(), half = _mm_set1_ps(0.5f);
    const __m128 uc = _mm_min_ps(_mm_max_ps(u, zero), _mm_set1_ps(u_max_ - 0.5f));
    const __m128 wc = _mm_min_ps(_mm_max_ps(w, zero), _mm_set1_ps(w_max_ - 0.5f));
    const __m128 offset = _mm_set1_ps(float(kCoarseOffset)), step = _mm_set1_ps(1.0f / kCoarseStep);
    const __m128 cu = _mm_add_ps(_mm_mul_ps(_mm_sub_ps(uc, offset), step), half);
    const __m128 cw = _mm_add_ps(_mm_mul_ps(_mm_sub_ps(wc, offset), step), half);
    const __m128 lateral = _mm_mul_ps(_mm_set1_ps(view.lateral_per_depth), z);
    const __m128 coarse = _mm_and_ps(
        _mm_and_ps(_mm_cmpgt_ps(distance, _mm_mul_ps(_mm_set1_ps(float(kCoarseStep)), lateral)),
                   _mm_and_ps(_mm_cmpge_ps(cu, zero), _mm_cmpge_ps(cw, zero))),
        _mm_and_ps(_mm_cmplt_ps(cu, _mm_set1_ps(cu_max_)), _mm_cmplt_ps(cw, _mm_set1_ps(cw_max_))));
    const __m128 near = _mm_cmple_ps(distance, lateral);  // !(distance > lateral), no NaNs
    alignas(16) float zs[4];
    alignas(16) int32_t pu[4], pw[4], iu[4], iw[4];
    _mm_store_ps(zs, z);
    _mm_store_si128(reinterpret_cast<__m128i*>(pu), _mm_cvttps_epi32(_mm_add_ps(uc, half)));
    _mm_store_si128(reinterpret_cast<__m128i*>(pw), _mm_cvttps_epi32(_mm_add_ps(wc, half)));
    _mm_store_si128(reinterpret_cast<__m128i*>(iu), _mm_cvttps_epi32(cu));
    _mm_store_si128(reinterpret_cast<__m128i*>(iw), _mm_cvttps_epi32(cw));
    const int in_image_bits = _mm_movemask_ps(in_image), coarse_bits = _mm_movemask_ps(coarse),
              near_bits = _mm_movemask_ps(near);
    for (int l = 0; l < 4; ++l) {
      Probe& probe = probes[l];
      probe.z = zs[l];
      probe.in_image = (in_image_bits >> l) & 1;
      v[l]->in_frustum |= uint8_t(probe.in_image);
      probe.pixel = pw[l] * view.width + pu[l];
      probe.sample = ((coarse_bits >> l) & 1)
                         ? &view.coarse_depth[size_t(std::max(0, iw[l])) * size_t(view.coarse_width) +
                                              size_t(std::max(0, iu[l]))]
                         : &view.depth[probe.pixel];
      probe.near = (near_bits >> l) & 1;
      __builtin_prefetch(probe.sample);
      if (probe.near) __builtin_prefetch(&view.triangle[probe.pixel]);
    }
  }
#endif

  // Tests the voxels voxels[which[0..n)] (n <= 64): carved[which[i]] = result.
  void Test(Active* voxels, const int* which, int n, uint8_t* carved) const {
    Probe probes[64];
    int a = 0;
#if defined(__SSE2__)
    for (; a + 4 <= n; a += 4) Project4(voxels, which + a, probes + a);
#endif
    for (; a < n; ++a) probes[a] = Project(&voxels[which[a]]);
    for (int a = 0; a < n; ++a) carved[which[a]] = uint8_t(Carved(voxels[which[a]], probes[a]));
  }

  // Tests the voxels [begin, end), moving the uncarved ones (in order) to
  // out; returns how many.
  int CarveRun(Active* begin, Active* end, Active* out) const {
    constexpr int kBatch = 64;
    Probe probes[kBatch];
    int kept = 0;
    for (Active* batch = begin; batch < end; batch += kBatch) {
      const int n = int(std::min<ptrdiff_t>(kBatch, end - batch));
      int a = 0;
#if defined(__SSE2__)
      static constexpr int kLanes[kBatch] = {0,  1,  2,  3,  4,  5,  6,  7,  8,  9,  10, 11, 12,
                                             13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25,
                                             26, 27, 28, 29, 30, 31, 32, 33, 34, 35, 36, 37, 38,
                                             39, 40, 41, 42, 43, 44, 45, 46, 47, 48, 49, 50, 51,
                                             52, 53, 54, 55, 56, 57, 58, 59, 60, 61, 62, 63};
      for (; a + 4 <= n; a += 4) Project4(batch, kLanes + a, probes + a);
#endif
      for (; a < n; ++a) probes[a] = Project(&batch[a]);
      for (int a = 0; a < n; ++a) {
        const bool carved = Carved(batch[a], probes[a]);
        out[kept] = batch[a];
        kept += int(!carved);
      }
    }
    return kept;
  }

 private:
  const CarveView& view_;
  const std::vector<Triangle>& triangles_;
  const std::vector<int32_t>& triangle_index_;
  const float margin_, behind_guard_, on_plane_;
  const float u_max_, w_max_, cu_max_, cw_max_;
};

constexpr int kBlock = 4;  // voxels per block edge; its cells have 2 voxels per edge

// Bounding box and smallest distance of the voxels [begin, end).
void Bound(const Active* begin, const Active* end, Block* block) {
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  block->lo = Vec3::Constant(kInfinity);
  block->hi = Vec3::Constant(-kInfinity);
  block->min_distance = kInfinity;
  for (const Active* voxel = begin; voxel != end; ++voxel) {
    block->lo = block->lo.cwiseMin(voxel->position);
    block->hi = block->hi.cwiseMax(voxel->position);
    block->min_distance = std::min(block->min_distance, voxel->distance);
  }
}

// Carves the voxels with k in [k_begin, k_end): sets outside[v] = 1 for the
// voxels some view sees in front of the surface, or that no view sees.
void CarveSlab(const GridSpec& grid, const std::vector<CarveView>& views,
               const std::vector<Triangle>& triangles, const std::vector<int32_t>& triangle_index,
               const std::vector<float>& distance, float near_distance, const SdfOptions& options,
               int k_begin, int k_end, std::vector<uint8_t>* outside) {
  const float h = float(grid.voxel_size);
  const Vec3 origin = grid.origin.cast<float>();
  const float margin = float(options.carve_margin);
  const int nx = grid.dims.x(), ny = grid.dims.y();

  // Blocks of kBlock^3 voxels in raster order, their voxels ordered by cell;
  // the voxels of each block that may be near the surface for some view form
  // a block of their own, tested voxel by voxel.
  std::vector<Active> active;
  active.reserve(size_t(nx) * size_t(ny) * size_t(std::max(0, k_end - k_begin)));
  std::vector<Block> blocks;
  std::vector<Block> cells;  // 8 per block (the 2^3 cells of block b at 8 * b)
  std::vector<Active> near;
  for (int bk = k_begin; bk < k_end; bk += kBlock) {
    for (int bj = 0; bj < ny; bj += kBlock) {
      for (int bi = 0; bi < nx; bi += kBlock) {
        Block block;
        block.begin = int(active.size());
        near.clear();
        for (int cell = 0; cell < 8; ++cell) {
          const int ck = bk + 2 * (cell >> 2), cj = bj + 2 * ((cell >> 1) & 1), ci = bi + 2 * (cell & 1);
          for (int k = ck; k < std::min(k_end, ck + 2); ++k) {
            for (int j = cj; j < std::min(ny, cj + 2); ++j) {
              for (int i = ci; i < std::min(nx, ci + 2); ++i) {
                const int64_t v = grid.Index(i, j, k);
                (*outside)[size_t(v)] = 1;  // until found uncarved below
                const Active voxel{Vec3(origin.x() + h * float(i), origin.y() + h * float(j),
                                        origin.z() + h * float(k)),
                                   distance[size_t(v)], int32_t(v), 0, uint8_t(cell)};
                (voxel.distance <= near_distance ? near : active).push_back(voxel);
              }
            }
          }
        }
        block.count = int(active.size()) - block.begin;
        if (block.count > 0) {
          Bound(&active[size_t(block.begin)], active.data() + active.size(), &block);
          blocks.push_back(block);
          // Its cells: only counts here, bounds when first needed.
          cells.resize(cells.size() + 8);
          Block* cell = &cells[cells.size() - 8];
          for (int a = block.begin; a < int(active.size()); ++a) ++cell[active[size_t(a)].cell].count;
        }
        if (!near.empty()) {
          Block near_block;
          near_block.begin = int(active.size());
          near_block.count = int(near.size());
          near_block.per_voxel = true;
          active.insert(active.end(), near.begin(), near.end());
          blocks.push_back(near_block);
          cells.resize(cells.size() + 8);  // unused; keeps cells[8 * b] for block b
        }
      }
    }
  }

  // View by view (its depth image stays in cache): each view first tries to
  // decide each block as a whole, then each 2^3 cell of an undecided block
  // (DecideBlock); the rest is tested voxel by voxel.
  int64_t remaining = int64_t(active.size());
  for (const CarveView& view : views) {
    if (remaining == 0) break;
    const VoxelCarver carver(view, triangles, triangle_index, h, margin);
    for (size_t b = 0; b < blocks.size(); ++b) {
      Block& block = blocks[b];
      if (block.count == 0) continue;
      Active* segment = &active[size_t(block.begin)];
      int kept = 0;
      if (block.per_voxel) {
        kept = carver.CarveRun(segment, segment + block.count, segment);
      } else {
        const BlockDecision decision = DecideBlock(view, block, margin);
        if (decision == BlockDecision::kOutOfView) continue;
        if (decision == BlockDecision::kNoneCarved) {
          // All voxels are in the image (or were, for an earlier view).
          block.seen = true;
          continue;
        }
        if (decision == BlockDecision::kAllCarved) {
          remaining -= block.count;
          block.count = 0;
          continue;
        }
        // Decide the 2^3 cells; the voxels of undecided cells are tested together.
        uint8_t carved[kBlock * kBlock * kBlock];
        int undecided[kBlock * kBlock * kBlock];
        int num_undecided = 0;
        Block* cell = &cells[8 * b];
        for (int c = 0, a = 0; c < 8; ++c) {
          const int end = a + cell[c].count;
          if (end == a) continue;
          if (cell[c].stale) {
            Bound(segment + a, segment + end, &cell[c]);
            cell[c].stale = false;
          }
          cell[c].seen = block.seen;
          const BlockDecision cell_decision = DecideBlock(view, cell[c], margin);
          // Not carved and all in the image: they are in the frustum.
          const uint8_t seen = uint8_t(cell_decision == BlockDecision::kNoneCarved);
          for (; a < end; ++a) {
            carved[a] = uint8_t(cell_decision == BlockDecision::kAllCarved);
            segment[a].in_frustum |= seen;
            if (cell_decision == BlockDecision::kUndecided) undecided[num_undecided++] = a;
          }
        }
        carver.Test(segment, undecided, num_undecided, carved);
        for (int a = 0; a < block.count; ++a) {
          if (carved[a]) {
            Block& owner = cell[segment[a].cell];
            --owner.count;
            owner.stale = true;
          }
          segment[kept] = segment[a];
          kept += int(!carved[a]);
        }
        if (kept > 0 && kept < block.count) Bound(segment, segment + kept, &block);
      }
      remaining -= block.count - kept;
      block.count = kept;
    }
  }
  // Uncarved voxels are inside, unless no view can see them.
  for (const Block& block : blocks) {
    for (int a = block.begin; a < block.begin + block.count; ++a) {
      const Active& voxel = active[size_t(a)];
      (*outside)[size_t(voxel.index)] = (voxel.in_frustum || block.seen) ? 0 : 1;
    }
  }
}


// Calls visit(u) for each of the (up to six) face neighbours u of the voxel
// with linear index v, in the order -x, +x, -y, +y, -z, +z.
template <typename Visit>
void ForEachFaceNeighbour(const GridSpec& grid, int64_t v, Visit&& visit) {
  const int nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  const int64_t sy = nx, sz = int64_t(nx) * ny;
  const int i = int(v % nx), j = int((v / nx) % ny), k = int(v / sz);
  if (i > 0) visit(v - 1);
  if (i < nx - 1) visit(v + 1);
  if (j > 0) visit(v - sy);
  if (j < ny - 1) visit(v + sy);
  if (k > 0) visit(v - sz);
  if (k < nz - 1) visit(v + sz);
}

// The closing of the seen surface with radius tau = radius_voxels * h
// (docs/sdf.md, "Sign"): O = the voxels farther than tau from the surface
// that a 6-connected flood fill reaches from the grid's border, starting at
// border voxels that the carving also calls outside (a body cut by the grid
// border does not seed the fill). A voxel in O is outside. So is every voxel
// in the open ball of radius d(o) around some o in O: that ball holds no
// surface, so it lies wholly on o's side (exact up to the grid). Voxels
// within tau of the surface look for such a ball among the O voxels within
// tau + 1.5 h; voxels on the surface (d <= 1e-3 h, no direction) keep the
// carving's word. Every other voxel is inside: gaps narrower than about 2 tau
// are closed, and concave corners keep their shape (they are covered by the
// balls of the O voxels beyond them). Returns false, leaving *closed_outside
// empty, when no border voxel can seed the fill.
bool ClosingOutside(const GridSpec& grid, const std::vector<float>& distance,
                    const std::vector<uint8_t>& carved,
                    float radius_voxels, std::vector<uint8_t>* closed_outside) {
  const int nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  const size_t n = distance.size();
  const float h = float(grid.voxel_size);
  const float tau = radius_voxels * h;
  std::vector<uint8_t> fill(n, 0);
  std::vector<int32_t> queue;
  queue.reserve(n / 4);
  auto seed = [&](int i, int j, int k) {
    const int64_t v = grid.Index(i, j, k);
    if (!fill[size_t(v)] && carved[size_t(v)] && distance[size_t(v)] > tau) {
      fill[size_t(v)] = 1;
      queue.push_back(int32_t(v));
    }
  };
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        if (i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1) seed(i, j, k);
      }
    }
  }
  if (queue.empty()) return false;
  for (size_t head = 0; head < queue.size(); ++head) {
    const int64_t v = queue[head];
    ForEachFaceNeighbour(grid, v, [&](int64_t u) {
      if (!fill[size_t(u)] && distance[size_t(u)] > tau) {
        fill[size_t(u)] = 1;
        queue.push_back(int32_t(u));
      }
    });
  }
  closed_outside->assign(n, 0);
  const int reach = int(std::ceil(radius_voxels + 1.5f));
  // Neighbour offsets within the search radius, nearest first (an early hit is likely).
  struct Offset {
    int di, dj, dk;
    float squared_voxels;
  };
  std::vector<Offset> offsets;
  for (int dk = -reach; dk <= reach; ++dk) {
    for (int dj = -reach; dj <= reach; ++dj) {
      for (int di = -reach; di <= reach; ++di) {
        const float r2 = float(di * di + dj * dj + dk * dk);
        if (r2 > 0.0f && r2 <= float(reach * reach)) offsets.push_back({di, dj, dk, r2});
      }
    }
  }
  std::stable_sort(offsets.begin(), offsets.end(),
                   [](const Offset& a, const Offset& b) { return a.squared_voxels < b.squared_voxels; });
  std::vector<int64_t> steps(offsets.size());  // linear index step of each offset
  for (size_t q = 0; q < offsets.size(); ++q) {
    steps[q] = offsets[q].di + int64_t(nx) * (offsets[q].dj + int64_t(ny) * offsets[q].dk);
  }
  const float on_surface = 1e-3f * h;
  const float h2 = h * h;
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const size_t v = size_t(grid.Index(i, j, k));
        if (fill[v]) {
          (*closed_outside)[v] = 1;
          continue;
        }
        const float d = distance[v];
        if (d > tau) continue;  // enclosed: inside
        if (!(d > on_surface)) {
          (*closed_outside)[v] = carved[v];  // on the surface
          continue;
        }
        // At least `reach` voxels from the border every offset stays in the
        // grid: linear index steps, no bounds checks (the same offsets in the
        // same order, so the same answer).
        const bool interior =
            i >= reach && j >= reach && k >= reach && i < nx - reach && j < ny - reach && k < nz - reach;
        if (interior) {
          for (size_t q = 0; q < offsets.size(); ++q) {
            const size_t u = size_t(int64_t(v) + steps[q]);
            if (fill[u] && offsets[q].squared_voxels * h2 < distance[u] * distance[u]) {
              (*closed_outside)[v] = 1;
              break;
            }
          }
          continue;
        }
        for (const Offset& o : offsets) {
          const int oi = i + o.di, oj = j + o.dj, ok = k + o.dk;
          if (oi < 0 || oj < 0 || ok < 0 || oi >= nx || oj >= ny || ok >= nz) continue;
          const size_t u = size_t(grid.Index(oi, oj, ok));
          if (fill[u] && o.squared_voxels * h2 < distance[u] * distance[u]) {
            (*closed_outside)[v] = 1;
            break;
          }
        }
      }
    }
  }
  return true;
}

// Number of 6-connected components of the inside voxels (outside[v] == 0)
// and the share of the inside voxels in the largest one (0 when none).
void InsideComponents(const GridSpec& grid, const std::vector<uint8_t>& outside,
                      int* num_components, double* largest_share) {
  std::vector<uint8_t> visited(outside.size(), 0);
  std::vector<int32_t> stack;
  int64_t total = 0, largest = 0;
  *num_components = 0;
  for (size_t start = 0; start < outside.size(); ++start) {
    if (outside[start] || visited[start]) continue;
    ++*num_components;
    int64_t size = 0;
    visited[start] = 1;
    stack.assign(1, int32_t(start));
    while (!stack.empty()) {
      const int64_t v = stack.back();
      stack.pop_back();
      ++size;
      ForEachFaceNeighbour(grid, v, [&](int64_t u) {
        if (!outside[size_t(u)] && !visited[size_t(u)]) {
          visited[size_t(u)] = 1;
          stack.push_back(int32_t(u));
        }
      });
    }
    total += size;
    largest = std::max(largest, size);
  }
  *largest_share = total > 0 ? double(largest) / double(total) : 0.0;
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
  triangles.reserve(size_t(std::count(scan.triangle_seen.begin(), scan.triangle_seen.end(), uint8_t(1))) +
                    1);
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

  auto lap = [last = start]() mutable {
    const auto now = std::chrono::steady_clock::now();
    const double seconds = std::chrono::duration<double>(now - last).count();
    last = now;
    return seconds;
  };
  Sdf sdf;
  sdf.summary.setup_seconds = lap();

  // 1a. Exact narrow band.
  const float band = float(grid.voxel_size);
  DistanceField field;
  field.squared.assign(num_voxels, std::numeric_limits<float>::infinity());
  field.x.assign(num_voxels, kFar);
  field.y.assign(num_voxels, kFar);
  field.z.assign(num_voxels, kFar);
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

  sdf.summary.band_seconds = lap();

  // 1b. Propagation to the whole grid (serial: each pass depends on the previous voxels).
  PropagatePass(grid, +1, &field);
  PropagatePass(grid, -1, &field);
  PropagatePass(grid, +1, &field);
  PropagatePass(grid, -1, &field);
  std::vector<float> distance(num_voxels);
  for (size_t v = 0; v < num_voxels; ++v) distance[v] = std::sqrt(field.squared[v]);
  field = DistanceField();

  sdf.summary.propagation_seconds = lap();

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
    BuildViewTables(&carve);
    views.push_back(std::move(carve));
  }
  // Voxels within this distance of the surface may be "near" (docs/sdf.md) for
  // some view: the largest lateral_per_depth times the largest camera depth
  // of a grid corner (an upper bound of every voxel's depth).
  float near_distance = 0.0f;
  for (const CarveView& view : views) {
    float farthest = 0.0f;
    for (int c = 0; c < 8; ++c) {
      const Vec3 corner(float((c & 1) ? grid.MaxCorner().x() : grid.MinCorner().x()),
                        float((c & 2) ? grid.MaxCorner().y() : grid.MinCorner().y()),
                        float((c & 4) ? grid.MaxCorner().z() : grid.MinCorner().z()));
      farthest = std::max(farthest, (corner - view.camera_center).norm());
    }
    near_distance = std::max(near_distance, view.lateral_per_depth * farthest * 1.001f + 1e-6f);
  }
  std::vector<uint8_t> outside(num_voxels, 0);
  for_each_slab([&](int k_begin, int k_end) {
    CarveSlab(grid, views, triangles, triangle_index, distance, near_distance, options, k_begin,
              k_end, &outside);
  });

  sdf.summary.carving_seconds = lap();

  // 3. Closing, and the sign: inside where either says inside.
  int64_t carving_inside = 0;
  for (size_t v = 0; v < num_voxels; ++v) carving_inside += int64_t(!outside[v]);
  std::vector<uint8_t> closed_outside;
  // kCarving: the sign before issue 14, no closing (closing_inside_fraction stays 0).
  const bool closing = options.sign == SdfOptions::Sign::kCarvingAndClosing &&
                       ClosingOutside(grid, distance, outside, float(options.closing_radius_voxels),
                                      &closed_outside);
  int64_t closing_inside = 0, disagree = 0;
  if (closing) {
    for (size_t v = 0; v < num_voxels; ++v) {
      closing_inside += int64_t(!closed_outside[v]);
      disagree += int64_t(closed_outside[v] != outside[v]);
    }
    for (size_t v = 0; v < num_voxels; ++v) outside[v] &= closed_outside[v];
  }
  sdf.summary.carving_inside_fraction = double(carving_inside) / double(num_voxels);
  sdf.summary.closing_inside_fraction = double(closing_inside) / double(num_voxels);

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
  sdf.summary.sign_disagreement = inside > 0 ? double(disagree) / double(inside) : 0.0;
  InsideComponents(grid, outside, &sdf.summary.num_inside_components,
                   &sdf.summary.largest_component_share);
  sdf.summary.closing_seconds = lap();
  sdf.summary.num_seen_triangles = int(triangles.size());
  sdf.summary.inside_fraction = double(inside) / double(num_voxels);
  sdf.summary.sign_ok = sdf.summary.inside_fraction >= options.min_inside_fraction;
  sdf.summary.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return sdf;
}

}  // namespace samp
