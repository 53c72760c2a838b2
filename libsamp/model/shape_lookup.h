// Fast trilinear lookups of phi_z = W z + mu for the fitter's cost functions.
// The model's components are re-laid out once, voxel-major (W_1 .. W_R
// contiguous per voxel, floats as in the model), so that d phi / dz reads 8
// contiguous rows of R numbers. Two ways to get the value:
//  - Evaluate(z, ..): the 8 corner values mu_c + W_c z, ~8 (R + 1) multiply-adds;
//  - EvaluateDense(phi, ..) on phi_z sampled on the whole grid once
//    (DenseCached(z)): 8 reads. The fitter evaluates ~10^5 points per code,
//    so it pays the D (R + 1) multiply-adds of the dense grid once per
//    evaluation and then only reads.
// Outside rule (all lookups): outside the grid box the value is phi_z at the
// nearest box point plus the distance to the box, so the gradient never
// vanishes and -gradient points back into the grid.
// Immutable after construction; const methods are safe to call concurrently.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include "libsamp/core/grid_spec.h"
#include "libsamp/core/mesh.h"
#include "libsamp/model/shape_model.h"

#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace samp {

class ShapeLookup {
 public:
  // Copies (re-lays out) the model; throws samp::Error on inconsistent sizes.
  explicit ShapeLookup(const ShapeModel& model);

  int num_components() const { return num_components_; }
  const GridSpec& grid() const { return grid_; }
  // sigma_i = sqrt(eigenvalue_i), R values.
  const Eigen::VectorXd& sigmas() const { return sigmas_; }

  // phi_z(point) with optional d/dpoint (3) and d/dz (R). `z` holds R numbers,
  // `point` 3 (object frame, metres). Null gradient pointers are skipped.
  double Evaluate(const double* z, const double* point, double* d_point, double* d_z) const;
  double Evaluate(const Eigen::VectorXd& z, const Eigen::Vector3d& point,
                  Eigen::Vector3d* d_point = nullptr, Eigen::VectorXd* d_z = nullptr) const;

  // phi_z on the whole grid (D doubles, GridSpec::Index order), computed on
  // the first call for a code and cached per thread (the thread's last two
  // codes), so the frame blocks of one Ceres evaluation share it and the code
  // of a step is still there after a rejected trial step. The pointer is
  // valid until the same thread asks for another code (or another lookup's).
  const double* DenseCached(const double* z) const;

  // phi_z(point) from a dense grid `phi` = DenseCached(z), with optional
  // d/dpoint (3) and d/dz (R; independent of z: the trilinear weights on W).
  // Same value and gradients as Evaluate(z, ..) up to rounding.
  double EvaluateDense(const double* phi, const double* point, double* d_point, double* d_z) const;

  // Where a point inside the grid box falls: the index of its cell's first
  // corner (GridSpec::Index order) and the fractions inside the cell. One
  // cell serves the value, d/dpoint and d/dz of the point (DenseAt,
  // CodeGradientAt), so a caller that needs all of them locates it once.
  struct DenseCell {
    int64_t base;
    double f[3];
  };

  // The cell of `point` when it lies inside the grid box (false otherwise,
  // and for non-finite points: those take EvaluateDense's general path).
  bool LocateInside(const double* point, DenseCell* cell) const {
    const double* lo = grid_.origin.data();
    const double* hi = max_corner_.data();
    if (!(point[0] >= lo[0] && point[0] <= hi[0] && point[1] >= lo[1] && point[1] <= hi[1] && point[2] >= lo[2] &&
          point[2] <= hi[2])) {
      return false;
    }
    int i0[3];
    for (int a = 0; a < 3; ++a) {
      // point >= lo, so u >= 0 and int() floors it (as Locate's clamped cell).
      const double u = (point[a] - lo[a]) * inv_voxel_;
      const int i = std::min(int(u), grid_.dims[a] - 2);
      i0[a] = i;
      cell->f[a] = u - i;
    }
    const int64_t nx = grid_.dims.x(), nxy = nx * grid_.dims.y();
    cell->base = i0[0] + nx * i0[1] + nxy * i0[2];
    return true;
  }

  // EvaluateDense(phi, point, d_point, nullptr) of a point inside the grid
  // box, bit for bit, from its cell (LocateInside); null d_point: the value only.
  double DenseAt(const double* phi, const DenseCell& cell, double* d_point) const {
    const int64_t nx = grid_.dims.x(), nxy = nx * grid_.dims.y();
    const double* c = phi + cell.base;
    const double fx = cell.f[0], fy = cell.f[1], fz = cell.f[2];
    const double gx = 1.0 - fx, gy = 1.0 - fy, gz = 1.0 - fz;
    const double c00 = gx * c[0] + fx * c[1], c10 = gx * c[nx] + fx * c[nx + 1];
    const double c01 = gx * c[nxy] + fx * c[nxy + 1], c11 = gx * c[nxy + nx] + fx * c[nxy + nx + 1];
    const double c0 = gy * c00 + fy * c10, c1 = gy * c01 + fy * c11;
    if (d_point) {
      d_point[2] = (c1 - c0) * inv_voxel_;
      d_point[1] = (gz * (c10 - c00) + fz * (c11 - c01)) * inv_voxel_;
      d_point[0] = (gz * (gy * (c[1] - c[0]) + fy * (c[nx + 1] - c[nx])) +
                    fz * (gy * (c[nxy + 1] - c[nxy]) + fy * (c[nxy + nx + 1] - c[nxy + nx]))) *
                   inv_voxel_;
    }
    return gz * c0 + fz * c1 + 0.0;  // + the distance to the box, 0 inside (as EvaluateDense)
  }

  // EvaluateDense's d/dz (R values) of a point inside the grid box, bit for
  // bit, from its cell: the trilinear weights on the 8 corners' rows of W.
  void CodeGradientAt(const DenseCell& cell, double* d_z) const;

  // EvaluateDense(phi, point, nullptr, nullptr), bit for bit, inlined: the
  // ray marches' samples. Points inside the grid box take a short path (no
  // clamping); the others, and non-finite ones, the general one.
  double EvaluateDenseValue(const double* phi, const double* point) const {
    DenseCell cell;
    if (!LocateInside(point, &cell)) return EvaluateDenseValueOutside(phi, point);
    return DenseAt(phi, cell, nullptr);
  }

  // EvaluateDenseValue at two points at once, bit for bit: the ray marches'
  // samples of two rays. With SSE2 one lane per point does
  // EvaluateDenseValueOutside's operations in their order (the nearest box
  // point, LocateInside's cell there, DenseAt's sums plus the distance to the
  // box; inside the box the point itself plus 0, EvaluateDenseValue's value);
  // a non-finite point and builds without SSE2 take EvaluateDenseValue. The
  // lookup's constants are broadcast to both lanes once, when the pair is made
  // (one per march). Holds references to the lookup and to phi, which must
  // outlive it.
  class DenseValuePair {
   public:
    DenseValuePair(const ShapeLookup& lookup, const double* phi) : lookup_(lookup), phi_(phi) {
#ifdef __SSE2__
      const GridSpec& grid = lookup.grid_;
      for (int a = 0; a < 3; ++a) {
        lo_[a] = _mm_set1_pd(grid.origin[a]);
        hi_[a] = _mm_set1_pd(lookup.max_corner_[a]);
        last_cell_[a] = _mm_set1_pd(double(grid.dims[a] - 2));
      }
      inv_voxel_ = _mm_set1_pd(lookup.inv_voxel_);
      nx_ = grid.dims.x();
      nxy_ = nx_ * grid.dims.y();
      nx_lanes_ = _mm_set1_pd(double(nx_));
      nxy_lanes_ = _mm_set1_pd(double(nxy_));
#endif
    }

    // Whether Evaluate4 may be called: the CPU has AVX (checked once).
    static bool HasEvaluate4();
    // values[k] = EvaluateDenseValue(phi, (x[k], y[k], z[k])) for k = 0..3,
    // bit for bit: Evaluate's operations in four AVX lanes (no FMA), a
    // non-finite point taking EvaluateDenseValue. Only when HasEvaluate4().
    void Evaluate4(const double* x, const double* y, const double* z, double* values) const;

    // EvaluateInside for four points in four AVX lanes (no FMA), bit for bit:
    // false (nothing written) unless all four lie inside the grid box. Only
    // when HasEvaluate4().
    bool EvaluateInside4(const double* x, const double* y, const double* z, DenseCell* cells, double* values,
                         double (*g)[3]) const;

    // values[k] = EvaluateDenseValue(phi, (x[k], y[k], z[k])) for k = 0, 1.
    void Evaluate(const double* x, const double* y, const double* z, double* values) const {
#ifdef __SSE2__
      const __m128d p[3] = {_mm_loadu_pd(x), _mm_loadu_pd(y), _mm_loadu_pd(z)};
      // The nearest box point q = min(max(p, lo), hi) (std::max and std::min
      // with their operands' roles) and the squared distance to it, summed
      // from 0 over the axes in order.
      __m128d q[3], outside_sq = _mm_setzero_pd();
      for (int a = 0; a < 3; ++a) {
        q[a] = _mm_min_pd(hi_[a], _mm_max_pd(lo_[a], p[a]));
        const __m128d outside = _mm_sub_pd(p[a], q[a]);
        outside_sq = _mm_add_pd(outside_sq, _mm_mul_pd(outside, outside));
      }
      // Not finite (false for NaN): EvaluateDenseValue's NaN.
      if (_mm_movemask_pd(_mm_cmple_pd(outside_sq, _mm_set1_pd(std::numeric_limits<double>::max()))) != 3) {
        for (int k = 0; k < 2; ++k) {
          const double point[3] = {x[k], y[k], z[k]};
          values[k] = lookup_.EvaluateDenseValue(phi_, point);
        }
        return;
      }
      // LocateInside at q per lane: u = (q - lo) / voxel >= 0, the cell
      // i = min(int(u), dims - 2) (as a double: exact), the fraction u - i.
      __m128d f[3], i[3];
      for (int a = 0; a < 3; ++a) {
        const __m128d u = _mm_mul_pd(_mm_sub_pd(q[a], lo_[a]), inv_voxel_);
        i[a] = _mm_min_pd(_mm_cvtepi32_pd(_mm_cvttpd_epi32(u)), last_cell_[a]);
        f[a] = _mm_sub_pd(u, i[a]);
      }
      // The cells' first corners (integers far below 2^53: exact as doubles).
      const __m128d base = _mm_add_pd(_mm_add_pd(i[0], _mm_mul_pd(nx_lanes_, i[1])), _mm_mul_pd(nxy_lanes_, i[2]));
      const double* c0 = phi_ + int64_t(_mm_cvtsd_f64(base));
      const double* c1 = phi_ + int64_t(_mm_cvtsd_f64(_mm_unpackhi_pd(base, base)));
      // DenseAt's sums (lane 0 from c0's corners, lane 1 from c1's), plus the
      // distance (sqrt(+0) = +0 inside, where x + 0 + 0 = x + 0).
      const __m128d one = _mm_set1_pd(1.0);
      const __m128d gx = _mm_sub_pd(one, f[0]), gy = _mm_sub_pd(one, f[1]), gz = _mm_sub_pd(one, f[2]);
      auto along_x = [&](int64_t k) {  // gx c[k] + fx c[k + 1]
        const __m128d a = _mm_loadu_pd(c0 + k), b = _mm_loadu_pd(c1 + k);
        return _mm_add_pd(_mm_mul_pd(gx, _mm_unpacklo_pd(a, b)), _mm_mul_pd(f[0], _mm_unpackhi_pd(a, b)));
      };
      const __m128d c00 = along_x(0), c10 = along_x(nx_), c01 = along_x(nxy_), c11 = along_x(nxy_ + nx_);
      const __m128d cy0 = _mm_add_pd(_mm_mul_pd(gy, c00), _mm_mul_pd(f[1], c10));
      const __m128d cy1 = _mm_add_pd(_mm_mul_pd(gy, c01), _mm_mul_pd(f[1], c11));
      const __m128d v = _mm_add_pd(_mm_add_pd(_mm_mul_pd(gz, cy0), _mm_mul_pd(f[2], cy1)), _mm_setzero_pd());
      _mm_storeu_pd(values, _mm_add_pd(v, _mm_sqrt_pd(outside_sq)));
#else
      for (int k = 0; k < 2; ++k) {
        const double point[3] = {x[k], y[k], z[k]};
        values[k] = lookup_.EvaluateDenseValue(phi_, point);
      }
#endif
    }

    // EvaluateDense(phi, p_k, g[k], nullptr) of the points p_k = (x[k], y[k],
    // z[k]), k in [0, n), bit for bit, into values[k] (null g: the values
    // only), with in_cell[k] = LocateInside(p_k, &cells[k]) (cells[k] set
    // where true): four at a time when all four lie inside the grid box
    // (EvaluateInside4, HasEvaluate4()), else two at a time when both do
    // (EvaluateInside), else one at a time.
    // (Inline: the callers' short runs of slots take no call.)
    void EvaluateCells(int n, const double* x, const double* y, const double* z, DenseCell* cells, bool* in_cell,
                       double* values, double (*g)[3]) const;

    // When both points lie inside the grid box: their cells (LocateInside),
    // values and d/dpoint (DenseAt(phi, cell, g); null g: the values only),
    // bit for bit, and true. False otherwise (nothing written), and always
    // without SSE2.
    bool EvaluateInside(const double* x, const double* y, const double* z, DenseCell* cells, double* values,
                        double (*g)[3]) const {
#ifdef __SSE2__
      const __m128d p[3] = {_mm_loadu_pd(x), _mm_loadu_pd(y), _mm_loadu_pd(z)};
      // LocateInside's test in both lanes (false for NaN, as there).
      __m128d inside = _mm_and_pd(_mm_cmpge_pd(p[0], lo_[0]), _mm_cmple_pd(p[0], hi_[0]));
      for (int a = 1; a < 3; ++a) {
        inside = _mm_and_pd(inside, _mm_and_pd(_mm_cmpge_pd(p[a], lo_[a]), _mm_cmple_pd(p[a], hi_[a])));
      }
      if (_mm_movemask_pd(inside) != 3) return false;
      __m128d f[3], i[3];
      for (int a = 0; a < 3; ++a) {
        const __m128d u = _mm_mul_pd(_mm_sub_pd(p[a], lo_[a]), inv_voxel_);
        i[a] = _mm_min_pd(_mm_cvtepi32_pd(_mm_cvttpd_epi32(u)), last_cell_[a]);
        f[a] = _mm_sub_pd(u, i[a]);
        _mm_storel_pd(&cells[0].f[a], f[a]);
        _mm_storeh_pd(&cells[1].f[a], f[a]);
      }
      const __m128d base = _mm_add_pd(_mm_add_pd(i[0], _mm_mul_pd(nx_lanes_, i[1])), _mm_mul_pd(nxy_lanes_, i[2]));
      cells[0].base = int64_t(_mm_cvtsd_f64(base));
      cells[1].base = int64_t(_mm_cvtsd_f64(_mm_unpackhi_pd(base, base)));
      const double* c0 = phi_ + cells[0].base;
      const double* c1 = phi_ + cells[1].base;
      // DenseAt's sums and differences, in both lanes.
      const __m128d one = _mm_set1_pd(1.0);
      const __m128d gx = _mm_sub_pd(one, f[0]), gy = _mm_sub_pd(one, f[1]), gz = _mm_sub_pd(one, f[2]);
      // Row k's corners: first (c[k]) and second (c[k + 1]) in both lanes.
      __m128d first[4], second[4];
      const int64_t rows[4] = {0, nx_, nxy_, nxy_ + nx_};
      for (int k = 0; k < 4; ++k) {
        const __m128d a = _mm_loadu_pd(c0 + rows[k]), b = _mm_loadu_pd(c1 + rows[k]);
        first[k] = _mm_unpacklo_pd(a, b);
        second[k] = _mm_unpackhi_pd(a, b);
      }
      auto along_x = [&](int k) { return _mm_add_pd(_mm_mul_pd(gx, first[k]), _mm_mul_pd(f[0], second[k])); };
      const __m128d c00 = along_x(0), c10 = along_x(1), c01 = along_x(2), c11 = along_x(3);
      const __m128d cy0 = _mm_add_pd(_mm_mul_pd(gy, c00), _mm_mul_pd(f[1], c10));
      const __m128d cy1 = _mm_add_pd(_mm_mul_pd(gy, c01), _mm_mul_pd(f[1], c11));
      if (g) {
        const __m128d d2 = _mm_mul_pd(_mm_sub_pd(cy1, cy0), inv_voxel_);
        const __m128d d1 = _mm_mul_pd(
            _mm_add_pd(_mm_mul_pd(gz, _mm_sub_pd(c10, c00)), _mm_mul_pd(f[2], _mm_sub_pd(c11, c01))), inv_voxel_);
        auto dx = [&](int k) { return _mm_sub_pd(second[k], first[k]); };  // c[k + 1] - c[k]
        const __m128d d0 = _mm_mul_pd(
            _mm_add_pd(_mm_mul_pd(gz, _mm_add_pd(_mm_mul_pd(gy, dx(0)), _mm_mul_pd(f[1], dx(1)))),
                       _mm_mul_pd(f[2], _mm_add_pd(_mm_mul_pd(gy, dx(2)), _mm_mul_pd(f[1], dx(3))))),
            inv_voxel_);
        _mm_storel_pd(&g[0][0], d0);
        _mm_storeh_pd(&g[1][0], d0);
        _mm_storel_pd(&g[0][1], d1);
        _mm_storeh_pd(&g[1][1], d1);
        _mm_storel_pd(&g[0][2], d2);
        _mm_storeh_pd(&g[1][2], d2);
      }
      const __m128d v = _mm_add_pd(_mm_add_pd(_mm_mul_pd(gz, cy0), _mm_mul_pd(f[2], cy1)), _mm_setzero_pd());
      _mm_storeu_pd(values, v);
      return true;
#else
      (void)x, (void)y, (void)z, (void)cells, (void)values, (void)g;
      return false;
#endif
    }

   private:
    const ShapeLookup& lookup_;
    const double* phi_;
#ifdef __SSE2__
    __m128d lo_[3], hi_[3], last_cell_[3], inv_voxel_, nx_lanes_, nxy_lanes_;
    int64_t nx_, nxy_;
#endif
  };

  // EvaluateDense(phi, point, nullptr, nullptr), bit for bit, without the
  // derivatives' bookkeeping: the value at the nearest box point plus the
  // distance to the box (NaN for a non-finite point). The ray marches'
  // samples outside the box (a trace's first, at the box entry).
  double EvaluateDenseValueOutside(const double* phi, const double* point) const;

  // Dense phi_z on the grid (D floats, GridSpec::Index order).
  std::vector<float> Dense(const Eigen::VectorXd& z) const;

  // Bounding box of the voxels with phi_z < 0, refined by linear interpolation
  // of the zero crossing along each axis (object frame). Empty box when phi_z
  // is nowhere negative.
  AlignedBox InsideBox(const Eigen::VectorXd& z) const;

  // The size (x, y, z extent = length, height, width) of InsideBox linearised
  // about z: size(z + dz) ~ size + jacobian dz, the Jacobian by central
  // differences over +-step sigma_i along each component (the box moves in
  // voxel-sized kinks, so a step of a fraction of sigma smooths them).
  // Returns false when the box is empty at z or at a step.
  struct BoxSizeLinearisation {
    Eigen::Vector3d size = Eigen::Vector3d::Zero();
    Eigen::Matrix<double, 3, Eigen::Dynamic> jacobian;
  };
  bool LineariseInsideBoxSize(const Eigen::VectorXd& z, double step, BoxSizeLinearisation* out) const;

 private:
  GridSpec grid_;
  int num_components_ = 0;
  uint64_t id_ = 0;                  // tags this lookup's entries in the per-thread cache
  std::vector<float> mean_;          // D (the model's floats: nothing is lost)
  std::vector<float> components_;    // D x R, voxel-major
  Eigen::VectorXd sigmas_;
  Eigen::Vector3d max_corner_;
  double inv_voxel_ = 1.0;
  double max_abs_mean_ = 0.0;       // max |mu_v|
  double max_abs_component_ = 0.0;  // max |W_vr|
};

inline void ShapeLookup::DenseValuePair::EvaluateCells(int n, const double* x, const double* y, const double* z,
                                                       DenseCell* cells, bool* in_cell, double* values,
                                                       double (*g)[3]) const {
  auto one = [&](int k) {
    const double p[3] = {x[k], y[k], z[k]};
    in_cell[k] = lookup_.LocateInside(p, &cells[k]);
    values[k] = in_cell[k] ? lookup_.DenseAt(phi_, cells[k], g ? g[k] : nullptr)
                           : lookup_.EvaluateDense(phi_, p, g ? g[k] : nullptr, nullptr);
  };
  // The points [k, end): two at a time, then one.
  auto pairs = [&](int k, int end) {
    for (; k + 2 <= end; k += 2) {
      if (EvaluateInside(x + k, y + k, z + k, cells + k, values + k, g ? g + k : nullptr)) {
        in_cell[k] = in_cell[k + 1] = true;
      } else {
        one(k);
        one(k + 1);
      }
    }
    if (k < end) one(k);
  };
  int k = 0;
  if (HasEvaluate4()) {
    for (; k + 4 <= n; k += 4) {
      if (EvaluateInside4(x + k, y + k, z + k, cells + k, values + k, g ? g + k : nullptr)) {
        for (int i = k; i < k + 4; ++i) in_cell[i] = true;
      } else {
        pairs(k, k + 4);
      }
    }
  }
  pairs(k, n);
}

}  // namespace samp
