#include "libsamp/model/shape_lookup.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "libsamp/core/error.h"

#ifdef __SSE2__
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define SAMP_AVX_KERNELS 1
#endif

namespace samp {

namespace {

std::atomic<uint64_t> next_lookup_id{1};

// Where a point falls in the grid: the 8 corner indices of its cell, the
// fractions inside it and the part of the point outside the grid box.
struct Cell {
  int64_t index[8];
  double f[3];
  double outside[3];
  bool clamped[3];
  double distance;  // to the grid box, 0 inside
};

// False for a non-finite point.
inline bool Locate(const GridSpec& grid, const Eigen::Vector3d& max_corner, double inv_voxel,
                   const double* point, Cell* cell) {
  double q[3];
  double outside_sq = 0.0;
  for (int a = 0; a < 3; ++a) {
    q[a] = std::min(std::max(point[a], grid.origin[a]), max_corner[a]);
    cell->outside[a] = point[a] - q[a];
    cell->clamped[a] = cell->outside[a] != 0.0;
    outside_sq += cell->outside[a] * cell->outside[a];
  }
  if (!std::isfinite(outside_sq)) return false;
  cell->distance = outside_sq > 0.0 ? std::sqrt(outside_sq) : 0.0;
  int i0[3];
  for (int a = 0; a < 3; ++a) {
    const double u = (q[a] - grid.origin[a]) * inv_voxel;
    const int i = std::min(std::max(int(u), 0), grid.dims[a] - 2);  // u >= 0: int() floors
    i0[a] = i;
    cell->f[a] = u - i;
  }
  const int64_t nx = grid.dims.x(), nxy = nx * grid.dims.y();
  const int64_t base = i0[0] + nx * i0[1] + nxy * i0[2];
  const int64_t offsets[8] = {0, 1, nx, nx + 1, nxy, nxy + 1, nxy + nx, nxy + nx + 1};
  for (int k = 0; k < 8; ++k) cell->index[k] = base + offsets[k];
  return true;
}

// Trilinear value of the corner values c (order x fastest) plus the distance
// to the box, and its gradient in the point (the box's outward direction on
// clamped axes).
inline double Interpolate(const Cell& cell, const double* c, double inv_voxel, double* d_point) {
  const double fx = cell.f[0], fy = cell.f[1], fz = cell.f[2];
  const double gx = 1.0 - fx, gy = 1.0 - fy, gz = 1.0 - fz;
  const double c00 = gx * c[0] + fx * c[1], c10 = gx * c[2] + fx * c[3];
  const double c01 = gx * c[4] + fx * c[5], c11 = gx * c[6] + fx * c[7];
  const double c0 = gy * c00 + fy * c10, c1 = gy * c01 + fy * c11;
  if (d_point) {
    double g[3];
    g[2] = (c1 - c0) * inv_voxel;
    g[1] = (gz * (c10 - c00) + fz * (c11 - c01)) * inv_voxel;
    g[0] = (gz * (gy * (c[1] - c[0]) + fy * (c[3] - c[2])) +
            fz * (gy * (c[5] - c[4]) + fy * (c[7] - c[6]))) *
           inv_voxel;
    for (int a = 0; a < 3; ++a) d_point[a] = cell.clamped[a] ? cell.outside[a] / cell.distance : g[a];
  }
  return gz * c0 + fz * c1 + cell.distance;
}

// d phi / dz = sum_k w_k W_k over the 8 corners; kR > 0 fixes R at compile time.
template <int kR>
inline void CodeGradient(const Cell& cell, const float* components, int num_components, double* d_z) {
  const int nr = kR > 0 ? kR : num_components;
  const double fx = cell.f[0], fy = cell.f[1], fz = cell.f[2];
  const double gx = 1.0 - fx, gy = 1.0 - fy, gz = 1.0 - fz;
  const double w[8] = {gx * gy * gz, fx * gy * gz, gx * fy * gz, fx * fy * gz,
                       gx * gy * fz, fx * gy * fz, gx * fy * fz, fx * fy * fz};
  double acc[kR > 0 ? kR : 1];
  double* out = kR > 0 ? acc : d_z;
  for (int r = 0; r < nr; ++r) out[r] = 0.0;
  for (int k = 0; k < 8; ++k) {
    const float* row = components + size_t(cell.index[k]) * nr;
    for (int r = 0; r < nr; ++r) out[r] += w[k] * double(row[r]);
  }
  if (kR > 0) {
    for (int r = 0; r < nr; ++r) d_z[r] = out[r];
  }
}

inline void CodeGradientAnyR(const Cell& cell, const float* components, int num_components, double* d_z) {
  switch (num_components) {
    case 5: return CodeGradient<5>(cell, components, 5, d_z);
    case 10: return CodeGradient<10>(cell, components, 10, d_z);
    default: return CodeGradient<0>(cell, components, num_components, d_z);
  }
}

double NaNResult(int num_components, double* d_point, double* d_z) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (d_point) d_point[0] = d_point[1] = d_point[2] = nan;
  if (d_z) std::fill(d_z, d_z + num_components, nan);
  return nan;
}

// phi_z = mu + W z on voxels [0, d) into out (double or float), each voxel's
// sum in the order mu, then r = 0 .. R - 1 (as Evaluate sums a corner); kR > 0
// fixes R at compile time.
template <int kR, typename Out>
void DenseKernel(const float* mean, const float* components, int num_components, const double* z, size_t d,
                 Out* out) {
  const size_t nr = kR > 0 ? size_t(kR) : size_t(num_components);
  for (size_t v = 0; v < d; ++v) {
    const float* row = components + v * nr;
    double s = mean[v];
    for (size_t r = 0; r < nr; ++r) s += double(row[r]) * z[r];
    out[v] = Out(s);
  }
}

#ifdef __SSE2__
// DenseKernel<5> two voxels at a time: lane k sums voxel v + k with
// DenseKernel's products in its order, so the same bits.
template <typename Out>
void DenseKernel5(const float* mean, const float* components, const double* z, size_t d, Out* out) {
  const __m128d z0 = _mm_set1_pd(z[0]), z1 = _mm_set1_pd(z[1]), z2 = _mm_set1_pd(z[2]);
  const __m128d z3 = _mm_set1_pd(z[3]), z4 = _mm_set1_pd(z[4]);
  // Two floats at p as doubles.
  auto load2 = [](const float* p) {
    return _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p))));
  };
  size_t v = 0;
  for (; v + 2 <= d; v += 2) {
    // w0 .. w9: the rows of voxels v and v + 1.
    const float* rows = components + v * 5;
    const __m128 w0123 = _mm_loadu_ps(rows), w4567 = _mm_loadu_ps(rows + 4);
    const __m128d w01 = _mm_cvtps_pd(w0123), w23 = _mm_cvtps_pd(_mm_movehl_ps(w0123, w0123));
    const __m128d w45 = _mm_cvtps_pd(w4567), w67 = _mm_cvtps_pd(_mm_movehl_ps(w4567, w4567));
    const __m128d w89 = load2(rows + 8);
    __m128d s = load2(mean + v);
    s = _mm_add_pd(s, _mm_mul_pd(_mm_shuffle_pd(w01, w45, 2), z0));  // (w0, w5)
    s = _mm_add_pd(s, _mm_mul_pd(_mm_shuffle_pd(w01, w67, 1), z1));  // (w1, w6)
    s = _mm_add_pd(s, _mm_mul_pd(_mm_shuffle_pd(w23, w67, 2), z2));  // (w2, w7)
    s = _mm_add_pd(s, _mm_mul_pd(_mm_shuffle_pd(w23, w89, 1), z3));  // (w3, w8)
    s = _mm_add_pd(s, _mm_mul_pd(_mm_shuffle_pd(w45, w89, 2), z4));  // (w4, w9)
    out[v] = Out(_mm_cvtsd_f64(s));
    out[v + 1] = Out(_mm_cvtsd_f64(_mm_unpackhi_pd(s, s)));
  }
  if (v < d) DenseKernel<5>(mean + v, components + v * 5, 5, z, d - v, out + v);
}
#endif

template <typename Out>
void DenseAnyR(const float* mean, const float* components, int num_components, const double* z, size_t d,
               Out* out) {
  switch (num_components) {
#ifdef __SSE2__
    case 5: return DenseKernel5(mean, components, z, d, out);
#else
    case 5: return DenseKernel<5>(mean, components, 5, z, d, out);
#endif
    case 10: return DenseKernel<10>(mean, components, 10, z, d, out);
    default: return DenseKernel<0>(mean, components, num_components, z, d, out);
  }
}

// phi_z = mu + W z at voxel v, as DenseKernel computes it (the same sum in
// the same order, then cast to float).
// kR > 0 fixes R at compile time.
template <int kR>
inline float VoxelValueR(const float* mean, const float* components, int num_components, const double* z,
                         int64_t v) {
  const int nr = kR > 0 ? kR : num_components;
  const float* row = components + size_t(v) * size_t(nr);
  double s = mean[v];
  for (int r = 0; r < nr; ++r) s += double(row[r]) * z[r];
  return float(s);
}

inline float VoxelValue(const float* mean, const float* components, int num_components, const double* z,
                        int64_t v) {
  return num_components == 5 ? VoxelValueR<5>(mean, components, 5, z, v)
                             : VoxelValueR<0>(mean, components, num_components, z, v);
}

// The inside box from the slices along each axis that hold an inside voxel
// (has[a][slice] != 0), the voxels' signs (negative(index)) and, where a
// crossing towards an outside neighbour is interpolated, their values
// (value(index)): the inside voxels' positions and those crossings, extreme
// in the first and last inside slices; the second slices are scanned too (a
// crossing one voxel back can tie the first slice's).
template <typename Negative, typename Value>
AlignedBox BoxFromSlices(const GridSpec& grid, const std::vector<uint8_t>* has, Negative negative, Value value) {
  const Eigen::Vector3i& n = grid.dims;
  const int64_t stride[3] = {1, int64_t(n.x()), int64_t(n.x()) * n.y()};
  // The first and last slice holding an inside voxel along each axis: the
  // scans below skip the rows outside them (no inside voxel there).
  int first[3], last[3];
  for (int a = 0; a < 3; ++a) {
    int lo = 0, hi = n[a] - 1;
    while (lo < n[a] && !has[a][size_t(lo)]) ++lo;
    if (lo == n[a]) return AlignedBox();  // phi_z >= 0 everywhere
    while (!has[a][size_t(hi)]) --hi;
    first[a] = lo;
    last[a] = hi;
  }
  AlignedBox box;
  for (int a = 0; a < 3; ++a) {
    const int lo = first[a], hi = last[a];
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    auto scan = [&](int slice, int side, double* extreme) {
      if (slice < 0 || slice >= n[a]) return;
      const double position = grid.origin[a] + grid.voxel_size * double(slice);
      const bool has_neighbour = slice + side >= 0 && slice + side < n[a];
      for (int q = first[c]; q <= last[c]; ++q) {
        for (int p = first[b]; p <= last[b]; ++p) {
          const int64_t index = slice * stride[a] + p * stride[b] + q * stride[c];
          if (!negative(index)) continue;
          double x = position;
          if (has_neighbour) {
            const int64_t neighbour = index + side * stride[a];
            if (!negative(neighbour)) {
              const float v = value(index), w = value(neighbour);
              const double e = position + side * grid.voxel_size * double(v) / double(v - w);
              x = side < 0 ? std::min(x, e) : std::max(x, e);
            }
          }
          *extreme = side < 0 ? std::min(*extreme, x) : std::max(*extreme, x);
        }
      }
    };
    double low = std::numeric_limits<double>::infinity(), high = -low;
    scan(lo, -1, &low);
    scan(lo + 1, -1, &low);
    scan(hi, +1, &high);
    scan(hi - 1, +1, &high);
    box.min[a] = low;
    box.max[a] = high;
  }
  return box;
}

// The slices along each axis that hold a voxel with negative(row[i]) (all
// voxels scanned; values: phi or its signs, in GridSpec::Index order).
template <typename T, typename Negative>
void InsideSlices(const GridSpec& grid, const T* values, Negative negative, std::vector<uint8_t>* has) {
  const Eigen::Vector3i& n = grid.dims;
  for (int a = 0; a < 3; ++a) has[a].assign(size_t(n[a]), 0);
  // Locals: stores through has_x may alias anything, so the row loop reads
  // nothing else from memory.
  const int nx = n.x();
  uint8_t* const has_x = has[0].data();
  for (int k = 0; k < n.z(); ++k) {
    for (int j = 0; j < n.y(); ++j) {
      const T* row = values + grid.Index(0, j, k);
      uint8_t any = 0;
      for (int i = 0; i < nx; ++i) {
        const uint8_t inside = negative(row[i]);
        has_x[i] |= inside;
        any |= inside;
      }
      has[1][size_t(j)] |= any;
      has[2][size_t(k)] |= any;
    }
  }
}

// A per-thread dense grid and its code (DenseCached keeps two).
struct DenseCache {
  uint64_t owner = 0;
  std::vector<double> code;
  std::vector<double> phi;
};

}  // namespace

ShapeLookup::ShapeLookup(const ShapeModel& model)
    : grid_(model.grid), id_(next_lookup_id.fetch_add(1)) {
  grid_.Check();
  const int64_t d = grid_.NumVoxels();
  num_components_ = int(model.components.cols());
  SAMP_CHECK(model.mean.size() == d)
      << "shape model: mean has " << model.mean.size() << " values, grid has " << d;
  SAMP_CHECK(model.components.rows() == d)
      << "shape model: components have " << model.components.rows() << " rows, grid has " << d;
  SAMP_CHECK(model.eigenvalues.size() == num_components_)
      << "shape model: " << model.eigenvalues.size() << " eigenvalues for " << num_components_
      << " components";
  SAMP_CHECK(num_components_ >= 1) << "shape model has no components";
  SAMP_CHECK((model.eigenvalues.array() > 0.0).all()) << "shape model eigenvalues must be > 0";
  mean_.resize(size_t(d));
  components_.resize(size_t(d) * num_components_);
  for (int64_t v = 0; v < d; ++v) {
    mean_[size_t(v)] = model.mean[v];
    float* row = &components_[size_t(v) * num_components_];
    for (int r = 0; r < num_components_; ++r) row[r] = model.components(v, r);
  }
  for (size_t v = 0; v < mean_.size(); ++v) max_abs_mean_ = std::max(max_abs_mean_, std::abs(double(mean_[v])));
  for (const float w : components_) max_abs_component_ = std::max(max_abs_component_, std::abs(double(w)));
  sigmas_ = model.eigenvalues.cwiseSqrt();
  max_corner_ = grid_.MaxCorner();
  inv_voxel_ = 1.0 / grid_.voxel_size;
}

double ShapeLookup::Evaluate(const double* z, const double* point, double* d_point,
                             double* d_z) const {
  Cell cell;
  if (!Locate(grid_, max_corner_, inv_voxel_, point, &cell)) return NaNResult(num_components_, d_point, d_z);
  double c[8];
  for (int k = 0; k < 8; ++k) {
    const float* row = &components_[size_t(cell.index[k]) * num_components_];
    double s = mean_[size_t(cell.index[k])];
    for (int r = 0; r < num_components_; ++r) s += double(row[r]) * z[r];
    c[k] = s;
  }
  if (d_z) CodeGradientAnyR(cell, components_.data(), num_components_, d_z);
  return Interpolate(cell, c, inv_voxel_, d_point);
}

double ShapeLookup::EvaluateDense(const double* phi, const double* point, double* d_point,
                                  double* d_z) const {
  Cell cell;
  if (!Locate(grid_, max_corner_, inv_voxel_, point, &cell)) return NaNResult(num_components_, d_point, d_z);
  double c[8];
  for (int k = 0; k < 8; ++k) c[k] = phi[cell.index[k]];
  if (d_z) CodeGradientAnyR(cell, components_.data(), num_components_, d_z);
  return Interpolate(cell, c, inv_voxel_, d_point);
}

// CodeGradient's sums from a cell's first corner and fractions (the same
// weights, corners and order); kR > 0 fixes R at compile time.
template <int kR>
inline void CodeGradientFromBase(const float* components, int num_components, int64_t base, int64_t nx,
                                 int64_t nxy, const double* f, double* d_z) {
  const int nr = kR > 0 ? kR : num_components;
  const double fx = f[0], fy = f[1], fz = f[2];
  const double gx = 1.0 - fx, gy = 1.0 - fy, gz = 1.0 - fz;
  const double w[8] = {gx * gy * gz, fx * gy * gz, gx * fy * gz, fx * fy * gz,
                       gx * gy * fz, fx * gy * fz, gx * fy * fz, fx * fy * fz};
  const int64_t offsets[8] = {0, 1, nx, nx + 1, nxy, nxy + 1, nxy + nx, nxy + nx + 1};
  double acc[kR > 0 ? kR : 1];
  double* out = kR > 0 ? acc : d_z;
  for (int r = 0; r < nr; ++r) out[r] = 0.0;
  for (int k = 0; k < 8; ++k) {
    const float* row = components + size_t(base + offsets[k]) * size_t(nr);
    for (int r = 0; r < nr; ++r) out[r] += w[k] * double(row[r]);
  }
  if (kR > 0) {
    for (int r = 0; r < nr; ++r) d_z[r] = out[r];
  }
}

#ifdef __SSE2__
// CodeGradientFromBase<5> with R = 5 in two lanes of two and one scalar:
// per lane the same products and sums in the same order, so the same bits.
inline void CodeGradientFromBase5(const float* components, int64_t base, int64_t nx, int64_t nxy, const double* f,
                                  double* d_z) {
  const double fx = f[0], fy = f[1], fz = f[2];
  const double gx = 1.0 - fx, gy = 1.0 - fy, gz = 1.0 - fz;
  const double w[8] = {gx * gy * gz, fx * gy * gz, gx * fy * gz, fx * fy * gz,
                       gx * gy * fz, fx * gy * fz, gx * fy * fz, fx * fy * fz};
  const int64_t offsets[8] = {0, 1, nx, nx + 1, nxy, nxy + 1, nxy + nx, nxy + nx + 1};
  __m128d acc01 = _mm_setzero_pd(), acc23 = _mm_setzero_pd();
  double acc4 = 0.0;
  for (int k = 0; k < 8; ++k) {
    const float* row = components + size_t(base + offsets[k]) * 5;
    const __m128d wk = _mm_set1_pd(w[k]);
    const __m128d r01 = _mm_cvtps_pd(_mm_castpd_ps(_mm_load_sd(reinterpret_cast<const double*>(row))));
    const __m128d r23 = _mm_cvtps_pd(_mm_castpd_ps(_mm_load_sd(reinterpret_cast<const double*>(row + 2))));
    acc01 = _mm_add_pd(acc01, _mm_mul_pd(wk, r01));
    acc23 = _mm_add_pd(acc23, _mm_mul_pd(wk, r23));
    acc4 += w[k] * double(row[4]);
  }
  _mm_storeu_pd(d_z, acc01);
  _mm_storeu_pd(d_z + 2, acc23);
  d_z[4] = acc4;
}
#endif

#ifdef SAMP_AVX_KERNELS
namespace {

// CodeGradientFromBase<5> with components 0-3 in the four lanes of one AVX
// register and the fifth scalar: per lane the same products and sums in the
// same order, so the same bits (the target is AVX without FMA: no product
// is fused into its sum). Chosen at run time (kCpuHasAvx).
__attribute__((target("avx"))) void CodeGradientFromBase5Avx(const float* components, int64_t base, int64_t nx,
                                                               int64_t nxy, const double* f, double* d_z) {
  const double fx = f[0], fy = f[1], fz = f[2];
  const double gx = 1.0 - fx, gy = 1.0 - fy, gz = 1.0 - fz;
  const double w[8] = {gx * gy * gz, fx * gy * gz, gx * fy * gz, fx * fy * gz,
                       gx * gy * fz, fx * gy * fz, gx * fy * fz, fx * fy * fz};
  const int64_t offsets[8] = {0, 1, nx, nx + 1, nxy, nxy + 1, nxy + nx, nxy + nx + 1};
  __m256d acc = _mm256_setzero_pd();
  double acc4 = 0.0;
  for (int k = 0; k < 8; ++k) {
    const float* row = components + size_t(base + offsets[k]) * 5;
    acc = _mm256_add_pd(acc, _mm256_mul_pd(_mm256_set1_pd(w[k]), _mm256_cvtps_pd(_mm_loadu_ps(row))));
    acc4 += w[k] * double(row[4]);
  }
  _mm256_storeu_pd(d_z, acc);
  d_z[4] = acc4;
}

// Whether this CPU runs AVX instructions (and the OS saves their registers).
const bool kCpuHasAvx = [] {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx") != 0;
}();

}  // namespace

bool ShapeLookup::DenseValuePair::HasEvaluate4() { return kCpuHasAvx; }

namespace {

// Four points' trilinear lookups in four AVX lanes, each lane the pair's
// (and DenseAt's) operations in order: the cells, the corners of their rows
// along x, the sums. In: the points, inside the grid box. lanes 0 and 2 of a
// row come from one pair of loads, lanes 1 and 3 from the other.
struct Lookup4 {
  __m256d f[3], g[3];          // the fractions in the cells and 1 - f
  alignas(32) double base[4];  // the cells' first corners (GridSpec::Index)
  // Per row (0, nx, nxy, nxy + nx): its first and second corners and
  // g[0] first + f[0] second.
  __m256d first[4], second[4], along_x[4];
  __m256d cy0, cy1, value;  // the sums along y, then z (+ 0, as DenseAt)
};

__attribute__((target("avx"), always_inline)) inline void LookUp4(const GridSpec& grid, double inv_voxel,
                                                                   int64_t nx, int64_t nxy, const double* phi,
                                                                   const __m256d* p, Lookup4* out) {
  __m256d i[3];
  for (int a = 0; a < 3; ++a) {
    const __m256d u = _mm256_mul_pd(_mm256_sub_pd(p[a], _mm256_set1_pd(grid.origin[a])), _mm256_set1_pd(inv_voxel));
    i[a] = _mm256_min_pd(_mm256_cvtepi32_pd(_mm256_cvttpd_epi32(u)), _mm256_set1_pd(double(grid.dims[a] - 2)));
    out->f[a] = _mm256_sub_pd(u, i[a]);
    out->g[a] = _mm256_sub_pd(_mm256_set1_pd(1.0), out->f[a]);
  }
  // The cells' first corners (integers far below 2^53: exact as doubles).
  _mm256_store_pd(out->base, _mm256_add_pd(_mm256_add_pd(i[0], _mm256_mul_pd(_mm256_set1_pd(double(nx)), i[1])),
                                           _mm256_mul_pd(_mm256_set1_pd(double(nxy)), i[2])));
  const double* c[4];
  for (int k = 0; k < 4; ++k) c[k] = phi + int64_t(out->base[k]);
  const int64_t rows[4] = {0, nx, nxy, nxy + nx};
  for (int r = 0; r < 4; ++r) {
    const int64_t k = rows[r];
    const __m256d even = _mm256_set_m128d(_mm_loadu_pd(c[2] + k), _mm_loadu_pd(c[0] + k));
    const __m256d odd = _mm256_set_m128d(_mm_loadu_pd(c[3] + k), _mm_loadu_pd(c[1] + k));
    out->first[r] = _mm256_unpacklo_pd(even, odd);
    out->second[r] = _mm256_unpackhi_pd(even, odd);
    out->along_x[r] = _mm256_add_pd(_mm256_mul_pd(out->g[0], out->first[r]), _mm256_mul_pd(out->f[0], out->second[r]));
  }
  out->cy0 = _mm256_add_pd(_mm256_mul_pd(out->g[1], out->along_x[0]), _mm256_mul_pd(out->f[1], out->along_x[1]));
  out->cy1 = _mm256_add_pd(_mm256_mul_pd(out->g[1], out->along_x[2]), _mm256_mul_pd(out->f[1], out->along_x[3]));
  out->value = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(out->g[2], out->cy0), _mm256_mul_pd(out->f[2], out->cy1)),
                             _mm256_setzero_pd());
}

}  // namespace

__attribute__((target("avx"))) void ShapeLookup::DenseValuePair::Evaluate4(const double* x, const double* y,
                                                                          const double* z, double* values) const {
  const GridSpec& grid = lookup_.grid_;
  const __m256d p[3] = {_mm256_loadu_pd(x), _mm256_loadu_pd(y), _mm256_loadu_pd(z)};
  // Evaluate's steps in four lanes: the nearest box point and the squared
  // distance to it, summed from 0 over the axes in order.
  __m256d q[3], outside_sq = _mm256_setzero_pd();
  for (int a = 0; a < 3; ++a) {
    q[a] = _mm256_min_pd(_mm256_set1_pd(lookup_.max_corner_[a]), _mm256_max_pd(_mm256_set1_pd(grid.origin[a]), p[a]));
    const __m256d outside = _mm256_sub_pd(p[a], q[a]);
    outside_sq = _mm256_add_pd(outside_sq, _mm256_mul_pd(outside, outside));
  }
  if (_mm256_movemask_pd(_mm256_cmp_pd(outside_sq, _mm256_set1_pd(std::numeric_limits<double>::max()), _CMP_LE_OQ)) !=
      15) {
    for (int k = 0; k < 4; ++k) {
      const double point[3] = {x[k], y[k], z[k]};
      values[k] = lookup_.EvaluateDenseValue(phi_, point);
    }
    return;
  }
  // The lookup at q, plus the distance to the box (sqrt(+0) = +0 inside).
  Lookup4 at;
  LookUp4(grid, lookup_.inv_voxel_, nx_, nxy_, phi_, q, &at);
  _mm256_storeu_pd(values, _mm256_add_pd(at.value, _mm256_sqrt_pd(outside_sq)));
}

__attribute__((target("avx"))) bool ShapeLookup::DenseValuePair::EvaluateInside4(const double* x, const double* y,
                                                                                const double* z, DenseCell* cells,
                                                                                double* values,
                                                                                double (*g)[3]) const {
  const GridSpec& grid = lookup_.grid_;
  const __m256d p[3] = {_mm256_loadu_pd(x), _mm256_loadu_pd(y), _mm256_loadu_pd(z)};
  // EvaluateInside's steps in four lanes: LocateInside's test (false for NaN).
  __m256d inside = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
  for (int a = 0; a < 3; ++a) {
    inside = _mm256_and_pd(inside, _mm256_and_pd(_mm256_cmp_pd(p[a], _mm256_set1_pd(grid.origin[a]), _CMP_GE_OQ),
                                                 _mm256_cmp_pd(p[a], _mm256_set1_pd(lookup_.max_corner_[a]),
                                                               _CMP_LE_OQ)));
  }
  if (_mm256_movemask_pd(inside) != 15) return false;
  Lookup4 at;
  LookUp4(grid, lookup_.inv_voxel_, nx_, nxy_, phi_, p, &at);
  alignas(32) double fractions[3][4];
  for (int a = 0; a < 3; ++a) _mm256_store_pd(fractions[a], at.f[a]);
  for (int k = 0; k < 4; ++k) {
    cells[k].base = int64_t(at.base[k]);
    for (int a = 0; a < 3; ++a) cells[k].f[a] = fractions[a][k];
  }
  if (g) {
    // DenseAt's differences, in the four lanes.
    const __m256d inv_voxel = _mm256_set1_pd(lookup_.inv_voxel_);
    const __m256d* ax = at.along_x;  // c00, c10, c01, c11
    const __m256d d2 = _mm256_mul_pd(_mm256_sub_pd(at.cy1, at.cy0), inv_voxel);
    const __m256d d1 = _mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(at.g[2], _mm256_sub_pd(ax[1], ax[0])),
                                                   _mm256_mul_pd(at.f[2], _mm256_sub_pd(ax[3], ax[2]))),
                                     inv_voxel);
    __m256d dx[4];
    for (int r = 0; r < 4; ++r) dx[r] = _mm256_sub_pd(at.second[r], at.first[r]);  // c[k + 1] - c[k]
    const __m256d d0 = _mm256_mul_pd(
        _mm256_add_pd(
            _mm256_mul_pd(at.g[2], _mm256_add_pd(_mm256_mul_pd(at.g[1], dx[0]), _mm256_mul_pd(at.f[1], dx[1]))),
            _mm256_mul_pd(at.f[2], _mm256_add_pd(_mm256_mul_pd(at.g[1], dx[2]), _mm256_mul_pd(at.f[1], dx[3])))),
        inv_voxel);
    alignas(32) double d[3][4];
    _mm256_store_pd(d[0], d0);
    _mm256_store_pd(d[1], d1);
    _mm256_store_pd(d[2], d2);
    for (int k = 0; k < 4; ++k) {
      for (int a = 0; a < 3; ++a) g[k][a] = d[a][k];
    }
  }
  _mm256_storeu_pd(values, at.value);
  return true;
}
#else
bool ShapeLookup::DenseValuePair::EvaluateInside4(const double*, const double*, const double*, DenseCell*, double*,
                                                  double (*)[3]) const {
  return false;
}
bool ShapeLookup::DenseValuePair::HasEvaluate4() { return false; }
void ShapeLookup::DenseValuePair::Evaluate4(const double* x, const double* y, const double* z, double* values) const {
  for (int k = 0; k < 4; ++k) {
    const double point[3] = {x[k], y[k], z[k]};
    values[k] = lookup_.EvaluateDenseValue(phi_, point);
  }
}
#endif

void ShapeLookup::CodeGradientAt(const DenseCell& cell, double* d_z) const {
  const int64_t nx = grid_.dims.x(), nxy = nx * grid_.dims.y();
  const float* w = components_.data();
  switch (num_components_) {
#ifdef __SSE2__
    case 5:
#ifdef SAMP_AVX_KERNELS
      if (kCpuHasAvx) return CodeGradientFromBase5Avx(w, cell.base, nx, nxy, cell.f, d_z);
#endif
      return CodeGradientFromBase5(w, cell.base, nx, nxy, cell.f, d_z);
#else
    case 5: return CodeGradientFromBase<5>(w, 5, cell.base, nx, nxy, cell.f, d_z);
#endif
    case 10: return CodeGradientFromBase<10>(w, 10, cell.base, nx, nxy, cell.f, d_z);
    default: return CodeGradientFromBase<0>(w, num_components_, cell.base, nx, nxy, cell.f, d_z);
  }
}

double ShapeLookup::EvaluateDenseValueOutside(const double* phi, const double* point) const {
  // Locate's clamping and distance, then the clamped point's cell (inside the
  // box by construction) plus the distance, Interpolate's sum.
  double q[3];
  double outside_sq = 0.0;
  for (int a = 0; a < 3; ++a) {
    q[a] = std::min(std::max(point[a], grid_.origin[a]), max_corner_[a]);
    const double outside = point[a] - q[a];
    outside_sq += outside * outside;
  }
  if (!std::isfinite(outside_sq)) return std::numeric_limits<double>::quiet_NaN();
  const double distance = outside_sq > 0.0 ? std::sqrt(outside_sq) : 0.0;
  DenseCell cell{};  // set by LocateInside: q lies in the box
  LocateInside(q, &cell);
  return DenseAt(phi, cell, nullptr) + distance;
}

const double* ShapeLookup::DenseCached(const double* z) const {
  // The two most recent grids; slots[last] the most recent one.
  thread_local DenseCache slots[2];
  thread_local int last = 0;
  const size_t nr = size_t(num_components_);
  for (const int k : {last, 1 - last}) {
    const DenseCache& cache = slots[k];
    if (cache.owner == id_ && cache.code.size() == nr && std::equal(z, z + nr, cache.code.begin())) {
      last = k;
      return cache.phi.data();
    }
  }
  last = 1 - last;  // the older slot takes the new grid
  DenseCache& cache = slots[last];
  const size_t d = mean_.size();
  cache.owner = 0;  // invalid while being filled
  cache.code.assign(z, z + nr);
  cache.phi.resize(d);
  DenseAnyR(mean_.data(), components_.data(), num_components_, z, d, cache.phi.data());
  cache.owner = id_;
  return cache.phi.data();
}

double ShapeLookup::Evaluate(const Eigen::VectorXd& z, const Eigen::Vector3d& point,
                             Eigen::Vector3d* d_point, Eigen::VectorXd* d_z) const {
  SAMP_CHECK(z.size() == num_components_)
      << "shape code has " << z.size() << " values, model has " << num_components_;
  if (d_z && d_z->size() != num_components_) d_z->resize(num_components_);
  return Evaluate(z.data(), point.data(), d_point ? d_point->data() : nullptr,
                  d_z ? d_z->data() : nullptr);
}

std::vector<float> ShapeLookup::Dense(const Eigen::VectorXd& z) const {
  SAMP_CHECK(z.size() == num_components_)
      << "shape code has " << z.size() << " values, model has " << num_components_;
  std::vector<float> out(mean_.size());
  DenseAnyR(mean_.data(), components_.data(), num_components_, z.data(), mean_.size(), out.data());
  return out;
}

AlignedBox ShapeLookup::InsideBox(const Eigen::VectorXd& z) const {
  SAMP_CHECK(z.size() == num_components_)
      << "shape code has " << z.size() << " values, model has " << num_components_;
  // phi_z as floats (as Dense()) and its signs, in per-thread buffers.
  thread_local std::vector<float> phi;
  phi.resize(mean_.size());
  DenseAnyR(mean_.data(), components_.data(), num_components_, z.data(), mean_.size(), phi.data());
  std::vector<uint8_t> has[3];
  InsideSlices(grid_, phi.data(), [](float v) { return v < 0.0f; }, has);
  return BoxFromSlices(
      grid_, has, [&](int64_t v) { return phi[size_t(v)] < 0.0f; }, [&](int64_t v) { return phi[size_t(v)]; });
}

bool ShapeLookup::LineariseInsideBoxSize(const Eigen::VectorXd& z, double step,
                                         BoxSizeLinearisation* out) const {
  SAMP_CHECK(int(z.size()) == num_components_ && step > 0.0)
      << "LineariseInsideBoxSize: code of " << z.size() << " values (expected " << num_components_
      << ") or step " << step << " <= 0";
  // InsideBox at z and at z +- h e_i, the latter without their dense grids:
  // phi at z +- h e_i differs from phi_z by at most |W_vi| h at voxel v (up to
  // rounding, which `margin` bounds), so only the voxels with
  // |phi_z| <= max_i |W_vi| h_i (the band) can take another sign; their signs
  // are decided from phi_z where the bound allows, else from their value.
  // Every box equals InsideBox's at the same code, bit for bit.
  const int nr = num_components_;
  const size_t d = mean_.size();
  // phi_z in double: the thread's dense grid of z (DenseCached; its floats are
  // Dense()'s), shared with the evaluations at z that follow or precede.
  const double* base = DenseCached(z.data());
  thread_local std::vector<uint8_t> negative;
  thread_local std::vector<int64_t> band;
  negative.resize(d);
  // The buffer through a local pointer: the loops then skip the thread-local lookup.
  uint8_t* const is_negative = negative.data();
  // float(x) < 0 exactly when x < -2^-150 (nearer -2^-149, the smallest
  // float below zero, than -0; the tie rounds to even, -0): the same test
  // without a conversion per voxel.
  constexpr double kLargestToMinusZero = -0x1p-150;
  for (size_t v = 0; v < d; ++v) is_negative[v] = base[v] < kLargestToMinusZero;
  std::vector<uint8_t> has[3], core_has[3];
  InsideSlices(grid_, is_negative, [](uint8_t v) { return v != 0; }, has);
  const AlignedBox box = BoxFromSlices(
      grid_, has, [&](int64_t v) { return is_negative[size_t(v)] != 0; },
      [&](int64_t v) { return float(base[size_t(v)]); });
  if (box.IsEmpty()) return false;
  out->size = box.Size();
  out->jacobian.resize(3, nr);

  // The steps h_i as taken (z_i +- h minus z_i, rounded) and a bound on the
  // rounding of the sums mu + W z in double: (R + 1) ulp of their absolute terms.
  Eigen::VectorXd plus_step(nr), minus_step(nr);
  double largest = max_abs_mean_;
  for (int i = 0; i < nr; ++i) {
    const double h = step * sigmas_[i];
    plus_step[i] = std::abs((z[i] + h) - z[i]);
    minus_step[i] = std::abs((z[i] - h) - z[i]);
    largest += max_abs_component_ * (std::abs(z[i]) + 2.0 * h);
  }
  const double margin = 1e-12 * double(nr + 1) * largest + 1e-30;
  // The band, and the voxels inside at every step (negative stays set).
  const double widest = max_abs_component_ * std::max(plus_step.maxCoeff(), minus_step.maxCoeff());
  band.clear();
  for (size_t v = 0; v < d; ++v) {
    const double s = base[v];
    if (s > widest + margin) {
      is_negative[v] = 0;
      continue;
    }
    if (s < -widest - margin) {
      is_negative[v] = 1;
      continue;
    }
    const float* row = &components_[v * size_t(nr)];
    double reach = 0.0;
    for (int i = 0; i < nr; ++i) {
      reach = std::max(reach, std::abs(double(row[i])) * std::max(plus_step[i], minus_step[i]));
    }
    if (s > reach + margin) {
      is_negative[v] = 0;
    } else if (s < -reach - margin) {
      is_negative[v] = 1;
    } else {
      band.push_back(int64_t(v));
      is_negative[v] = 0;
    }
  }
  // The core's slices (the band's voxels are still unset).
  InsideSlices(grid_, is_negative, [](uint8_t v) { return v != 0; }, core_has);
  const int64_t nx = grid_.dims.x(), nxy = nx * grid_.dims.y();

  auto box_at = [&](const Eigen::VectorXd& code, int i, double taken) {
    for (int a = 0; a < 3; ++a) has[a] = core_has[a];
    for (const int64_t v : band) {
      const double s = base[size_t(v)];
      const double change = std::abs(double(components_[size_t(v) * size_t(nr) + size_t(i)])) * taken;
      bool inside;
      if (s - change > margin) {
        inside = false;
      } else if (s + change < -margin) {
        inside = true;
      } else {
        inside = VoxelValue(mean_.data(), components_.data(), nr, code.data(), v) < 0.0f;
      }
      is_negative[size_t(v)] = inside;
      if (inside) {
        const int64_t k = v / nxy, j = (v - k * nxy) / nx;
        has[0][size_t(v - k * nxy - j * nx)] = 1;
        has[1][size_t(j)] = 1;
        has[2][size_t(k)] = 1;
      }
    }
    return BoxFromSlices(
        grid_, has, [&](int64_t v) { return is_negative[size_t(v)] != 0; },
        [&](int64_t v) { return VoxelValue(mean_.data(), components_.data(), nr, code.data(), v); });
  };
  for (int i = 0; i < nr; ++i) {
    const double h = step * sigmas_[i];
    Eigen::VectorXd plus = z, minus = z;
    plus[i] += h;
    minus[i] -= h;
    const AlignedBox a = box_at(plus, i, plus_step[i]), b = box_at(minus, i, minus_step[i]);
    if (a.IsEmpty() || b.IsEmpty()) return false;
    out->jacobian.col(i) = (a.Size() - b.Size()) / (2.0 * h);
  }
  return true;
}

}  // namespace samp
