// The sign by visibility carving of ComputeSdf (sdf.cc, docs/sdf.md, "Sign:
// visibility carving"): a voxel is outside if some view sees it in front of
// the observed surface (or through empty space); near the surface the
// pixel-centre depth is replaced by the plane of the triangle the pixel saw,
// so the zero crossing does not depend on the pixel grid. Blocks and cells of
// voxels are decided as a whole where the per-voxel rule must give the same
// answer for all of them ("How the carving is evaluated").
#include <algorithm>
#include <cmath>
#include <limits>

#include "libsamp/core/error.h"
#include "libsamp/sdf/sdf_stages.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace samp {
namespace sdf_internal {
namespace {

constexpr int kCoarseStep = 4;
constexpr int kCoarseOffset = (kCoarseStep - 1) / 2;
constexpr int kCell = 8;

// The minimum and maximum depth over the pixels [u0, u1) x [v0, v1), NaNs
// ignored (+inf and -inf when there are none). std::min(m, x) = x < m ? x : m
// keeps a non-NaN running value against a NaN, so the result is the same in
// any order of the pixels (+0 and -0 aside, which every later comparison
// treats alike); _mm_min_ps(x, m) is x < m ? x : m lane by lane (and
// _mm_max_ps(x, m) is std::max(m, x)).
void CellMinMax(const float* depth, int width, int u0, int u1, int v0, int v1, float* lowest,
                float* highest) {
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  float lo = kInfinity, hi = -kInfinity;
#if defined(__SSE2__)
  static_assert(kCell == 8, "a full cell row is two SSE registers");
  if (u1 - u0 == kCell) {
    __m128 m0 = _mm_set1_ps(kInfinity), m1 = m0, x0 = _mm_set1_ps(-kInfinity), x1 = x0;
    const float* row = depth + int64_t(v0) * width + u0;
    for (int v = v0; v < v1; ++v, row += width) {
      const __m128 r0 = _mm_loadu_ps(row), r1 = _mm_loadu_ps(row + 4);
      m0 = _mm_min_ps(r0, m0);
      m1 = _mm_min_ps(r1, m1);
      x0 = _mm_max_ps(r0, x0);
      x1 = _mm_max_ps(r1, x1);
    }
    __m128 m = _mm_min_ps(m0, m1), x = _mm_max_ps(x0, x1);
    m = _mm_min_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
    x = _mm_max_ps(x, _mm_shuffle_ps(x, x, _MM_SHUFFLE(1, 0, 3, 2)));
    m = _mm_min_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)));
    x = _mm_max_ps(x, _mm_shuffle_ps(x, x, _MM_SHUFFLE(2, 3, 0, 1)));
    *lowest = _mm_cvtss_f32(m);
    *highest = _mm_cvtss_f32(x);
    return;
  }
#endif
  for (int v = v0; v < v1; ++v) {
    for (int u = u0; u < u1; ++u) {
      lo = std::min(lo, depth[int64_t(v) * width + u]);
      hi = std::max(hi, depth[int64_t(v) * width + u]);
    }
  }
  *lowest = lo;
  *highest = hi;
}

// Fills the coarse image and the min/max depth over cells of kCell x kCell
// pixels.
void BuildViewTables(CarveView* view) {
  const int width = view->width, height = view->height;
  view->coarse_width = std::max(0, (width - 1 - kCoarseOffset) / kCoarseStep + 1);
  view->coarse_height = std::max(0, (height - 1 - kCoarseOffset) / kCoarseStep + 1);
  view->coarse_depth.resize(size_t(view->coarse_width) * size_t(view->coarse_height));
  for (int cw = 0; cw < view->coarse_height; ++cw) {
    const float* row = view->depth + int64_t(kCoarseOffset + cw * kCoarseStep) * width + kCoarseOffset;
    float* coarse = &view->coarse_depth[size_t(cw) * size_t(view->coarse_width)];
    for (int cu = 0; cu < view->coarse_width; ++cu) coarse[cu] = row[cu * kCoarseStep];
  }
  view->cell_width = (width + kCell - 1) / kCell;
  view->cell_height = (height + kCell - 1) / kCell;
  view->cell_min.resize(size_t(view->cell_width) * size_t(view->cell_height));
  view->cell_max.resize(view->cell_min.size());
  for (int cw = 0; cw < view->cell_height; ++cw) {
    const int v0 = cw * kCell, v1 = std::min(height, v0 + kCell);
    for (int cu = 0; cu < view->cell_width; ++cu) {
      const size_t c = size_t(cw) * size_t(view->cell_width) + size_t(cu);
      CellMinMax(view->depth, width, cu * kCell, std::min(width, (cu + 1) * kCell), v0, v1,
                 &view->cell_min[c], &view->cell_max[c]);
    }
  }
}

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
  const Vec3& centre = block.centre;
  const float radius = block.radius;
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

// Bounding box (with its centre and radius) and smallest distance of the
// voxels [begin, end).
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
  block->centre = 0.5f * (block->lo + block->hi);
  block->radius = 0.5f * (block->hi - block->lo).norm() * 1.0001f + 1e-6f;
}

// The voxels of the block at (bi, bj, bk), cell by cell, appended to *far,
// or to *near when within near_distance of the surface; outside[v] = 1 for
// each until found uncarved.
void GatherBlock(const GridSpec& grid, const std::vector<float>& distance, float near_distance, int bi, int bj,
                 int bk, int k_end, std::vector<Active>* far, std::vector<Active>* near,
                 std::vector<uint8_t>* outside) {
  const float h = float(grid.voxel_size);
  const Vec3 origin = grid.origin.cast<float>();
  const int nx = grid.dims.x(), ny = grid.dims.y();
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
          (voxel.distance <= near_distance ? *near : *far).push_back(voxel);
        }
      }
    }
  }
}

// The block of the voxels active[begin, end) of *slab, with its 8 cells:
// only counts here, bounds when first needed.
void AddBlock(int begin, SlabVoxels* slab) {
  std::vector<Active>& active = slab->active;
  Block block;
  block.begin = begin;
  block.count = int(active.size()) - block.begin;
  Bound(&active[size_t(block.begin)], active.data() + active.size(), &block);
  slab->blocks.push_back(block);
  slab->cells.resize(slab->cells.size() + 8);
  Block* cell = &slab->cells[slab->cells.size() - 8];
  for (int a = block.begin; a < int(active.size()); ++a) ++cell[active[size_t(a)].cell].count;
}

// The near voxels of a block, appended to *slab as a block of their own.
void AddNearBlock(const std::vector<Active>& near, SlabVoxels* slab) {
  Block near_block;
  near_block.begin = int(slab->active.size());
  near_block.count = int(near.size());
  near_block.per_voxel = true;
  slab->active.insert(slab->active.end(), near.begin(), near.end());
  slab->blocks.push_back(near_block);
  slab->cells.resize(slab->cells.size() + 8);  // unused; keeps cells[8 * b] for block b
}

// The voxels with k in [k_begin, k_end) in blocks, in *slab (emptied first,
// its buffers reused); outside[v] = 1 for each.
void GatherSlab(const GridSpec& grid, const std::vector<float>& distance, float near_distance, int k_begin,
                int k_end, SlabVoxels* slab, std::vector<uint8_t>* outside) {
  const int nx = grid.dims.x(), ny = grid.dims.y();
  const size_t num_blocks = size_t((nx + kBlock - 1) / kBlock) * size_t((ny + kBlock - 1) / kBlock) *
                            size_t((std::max(0, k_end - k_begin) + kBlock - 1) / kBlock);
  slab->active.clear();
  slab->blocks.clear();
  slab->cells.clear();
  // At most a block and a near block per block of the grid, 8 cells each.
  slab->active.reserve(size_t(nx) * size_t(ny) * size_t(std::max(0, k_end - k_begin)));
  slab->blocks.reserve(2 * num_blocks);
  slab->cells.reserve(16 * num_blocks);
  std::vector<Active>& near = slab->near;
  for (int bk = k_begin; bk < k_end; bk += kBlock) {
    for (int bj = 0; bj < ny; bj += kBlock) {
      for (int bi = 0; bi < nx; bi += kBlock) {
        const int begin = int(slab->active.size());
        near.clear();
        GatherBlock(grid, distance, near_distance, bi, bj, bk, k_end, &slab->active, &near, outside);
        if (int(slab->active.size()) > begin) AddBlock(begin, slab);
        if (!near.empty()) AddNearBlock(near, slab);
      }
    }
  }
}

// Decides the 2^3 cells of an undecided block for one view (DecideBlock):
// carved[a] = 1 for the voxels of carved cells (carved[] starts at 0); the
// voxels of undecided cells listed in undecided, their number returned.
int DecideCells(const CarveView& view, float margin, const Block& block, Block* cell, Active* segment,
                uint8_t* carved, int* undecided) {
  int num_undecided = 0;
  for (int c = 0, a = 0; c < 8; ++c) {
    const int end = a + cell[c].count;
    if (end == a) continue;
    if (cell[c].stale) {
      Bound(segment + a, segment + end, &cell[c]);
      cell[c].stale = false;
    }
    cell[c].seen = block.seen;
    switch (DecideBlock(view, cell[c], margin)) {
      case BlockDecision::kOutOfView:
        break;
      case BlockDecision::kNoneCarved:  // and all in the image: they are in the frustum
        for (int b = a; b < end; ++b) segment[b].in_frustum = 1;
        break;
      case BlockDecision::kAllCarved:
        std::fill(carved + a, carved + end, uint8_t(1));
        break;
      case BlockDecision::kUndecided:
        for (int b = a; b < end; ++b) undecided[num_undecided++] = b;
        break;
    }
    a = end;
  }
  return num_undecided;
}

// An undecided block (its voxels at segment): decides its 2^3 cells, then
// tests the voxels of the undecided cells together. Moves the uncarved
// voxels (in order) to the start of the segment; returns how many.
int CarveCells(const CarveView& view, const VoxelCarver& carver, float margin, Block* block, Block* cell,
               Active* segment) {
  uint8_t carved[kBlock * kBlock * kBlock] = {};
  int undecided[kBlock * kBlock * kBlock];
  const int num_undecided = DecideCells(view, margin, *block, cell, segment, carved, undecided);
  carver.Test(segment, undecided, num_undecided, carved);
  // The voxels before the first carved one stay where they are.
  int kept = 0;
  while (kept < block->count && !carved[kept]) ++kept;
  if (kept == block->count) return kept;
  for (int a = kept; a < block->count; ++a) {
    if (carved[a]) {
      Block& owner = cell[segment[a].cell];
      --owner.count;
      owner.stale = true;
    }
    segment[kept] = segment[a];
    kept += int(!carved[a]);
  }
  if (kept > 0 && kept < block->count) Bound(segment, segment + kept, block);
  return kept;
}

// Carves block b of *slab for one view: as a whole when DecideBlock can,
// else cell by cell and voxel by voxel. Moves the uncarved voxels (in order)
// to the start of its segment; returns how many.
int CarveBlock(const CarveView& view, const VoxelCarver& carver, float margin, size_t b, SlabVoxels* slab) {
  Block& block = slab->blocks[b];
  Active* segment = &slab->active[size_t(block.begin)];
  if (block.per_voxel) return carver.CarveRun(segment, segment + block.count, segment);
  const BlockDecision decision = DecideBlock(view, block, margin);
  if (decision == BlockDecision::kOutOfView) return block.count;
  if (decision == BlockDecision::kNoneCarved) {
    // All voxels are in the image (or were, for an earlier view).
    block.seen = true;
    return block.count;
  }
  if (decision == BlockDecision::kAllCarved) return 0;
  return CarveCells(view, carver, margin, &block, &slab->cells[8 * b], segment);
}

// Carves the voxels of *slab that one view carves; returns how many.
int64_t CarveWithView(const CarveView& view, const VoxelCarver& carver, float margin, SlabVoxels* slab) {
  int64_t carved = 0;
  for (size_t b = 0; b < slab->blocks.size(); ++b) {
    if (slab->blocks[b].count == 0) continue;
    const int kept = CarveBlock(view, carver, margin, b, slab);
    Block& block = slab->blocks[b];
    carved += block.count - kept;
    block.count = kept;
  }
  return carved;
}

// Uncarved voxels are inside, unless no view can see them.
void MarkUncarved(const SlabVoxels& slab, std::vector<uint8_t>* outside) {
  for (const Block& block : slab.blocks) {
    for (int a = block.begin; a < block.begin + block.count; ++a) {
      const Active& voxel = slab.active[size_t(a)];
      (*outside)[size_t(voxel.index)] = (voxel.in_frustum || block.seen) ? 0 : 1;
    }
  }
}

}  // namespace

void MakeCarveViews(const ScanResult& scan, std::vector<CarveView>* views) {
  views->resize(scan.views.size());
  for (size_t index = 0; index < scan.views.size(); ++index) {
    const ScanView& view = scan.views[index];
    const int64_t pixels = int64_t(view.camera.width) * view.camera.height;
    SAMP_CHECK(int64_t(view.depth.size()) == pixels && int64_t(view.triangle.size()) == pixels)
        << "ComputeSdf: scan view " << index << " has " << view.depth.size() << " depths and "
        << view.triangle.size() << " triangle ids for " << pixels << " pixels";
    CarveView& carve = (*views)[index];
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
  }
}

float NearDistance(const GridSpec& grid, const std::vector<CarveView>& views) {
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
  return near_distance;
}

void CarveSlab(const GridSpec& grid, const std::vector<CarveView>& views,
               const std::vector<Triangle>& triangles, const std::vector<int32_t>& triangle_index,
               const std::vector<float>& distance, float near_distance, const SdfOptions& options,
               int k_begin, int k_end, SlabVoxels* slab_out, std::vector<uint8_t>* outside) {
  const float h = float(grid.voxel_size);
  const float margin = float(options.carve_margin);
  SlabVoxels& slab = *slab_out;
  GatherSlab(grid, distance, near_distance, k_begin, k_end, &slab, outside);
  // View by view (its depth image stays in cache): each view first tries to
  // decide each block as a whole, then each 2^3 cell of an undecided block
  // (DecideBlock); the rest is tested voxel by voxel.
  int64_t remaining = int64_t(slab.active.size());
  for (const CarveView& view : views) {
    if (remaining == 0) break;
    const VoxelCarver carver(view, triangles, triangle_index, h, margin);
    remaining -= CarveWithView(view, carver, margin, &slab);
  }
  MarkUncarved(slab, outside);
}

}  // namespace sdf_internal
}  // namespace samp
