#include "libsamp/fit/shape_lookup.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "libsamp/core/error.h"

namespace samp {

ShapeLookup::ShapeLookup(const ShapeModel& model) : grid_(model.grid) {
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
  stride_ = num_components_ + 1;
  table_.resize(size_t(d) * stride_);
  for (int64_t v = 0; v < d; ++v) {
    double* row = &table_[size_t(v) * stride_];
    row[0] = model.mean[v];
    for (int r = 0; r < num_components_; ++r) row[1 + r] = model.components(v, r);
  }
  sigmas_ = model.eigenvalues.cwiseSqrt();
  max_corner_ = grid_.MaxCorner();
  inv_voxel_ = 1.0 / grid_.voxel_size;
}

namespace {

// The lookup with the number of components fixed at compile time (kR > 0)
// or at run time (kR = 0): the fixed version lets the compiler unroll the
// 8 x (R + 1) inner loops.
template <int kR>
double EvaluateKernel(const GridSpec& grid_, const Eigen::Vector3d& max_corner_, double inv_voxel_,
                      const std::vector<double>& table_, int num_components, const double* z,
                      const double* point, double* d_point, double* d_z) {
  const int nr = kR > 0 ? kR : num_components;
  const int stride_ = nr + 1;
  // Clamp to the grid box; remember which axes were clamped.
  double q[3], outside[3];
  bool clamped[3];
  double outside_sq = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double lo = grid_.origin[a], hi = max_corner_[a];
    q[a] = std::min(std::max(point[a], lo), hi);
    outside[a] = point[a] - q[a];
    clamped[a] = outside[a] != 0.0;
    outside_sq += outside[a] * outside[a];
  }
  if (!std::isfinite(outside_sq)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    if (d_point) d_point[0] = d_point[1] = d_point[2] = nan;
    if (d_z) std::fill(d_z, d_z + nr, nan);
    return nan;
  }
  int i0[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    const double u = (q[a] - grid_.origin[a]) * inv_voxel_;
    int i = int(std::floor(u));
    i = std::min(std::max(i, 0), grid_.dims[a] - 2);
    i0[a] = i;
    f[a] = u - i;
  }
  const int64_t nx = grid_.dims.x(), nxy = nx * grid_.dims.y();
  const int64_t base = i0[0] + nx * i0[1] + nxy * i0[2];
  const int64_t offsets[8] = {base,          base + 1,          base + nx,          base + nx + 1,
                              base + nxy,    base + nxy + 1,    base + nxy + nx,    base + nxy + nx + 1};
  // Corner values phi_c = mu_c + W_c z.
  double c[8];
  for (int k = 0; k < 8; ++k) {
    const double* row = &table_[size_t(offsets[k]) * stride_];
    double s = row[0];
    for (int r = 0; r < nr; ++r) s += row[1 + r] * z[r];
    c[k] = s;
  }
  const double fx = f[0], fy = f[1], fz = f[2];
  const double gx = 1.0 - fx, gy = 1.0 - fy, gz = 1.0 - fz;
  // Interpolate along x, then y, then z.
  const double c00 = gx * c[0] + fx * c[1], c10 = gx * c[2] + fx * c[3];
  const double c01 = gx * c[4] + fx * c[5], c11 = gx * c[6] + fx * c[7];
  const double c0 = gy * c00 + fy * c10, c1 = gy * c01 + fy * c11;
  double value = gz * c0 + fz * c1;
  const double distance = std::sqrt(outside_sq);
  value += distance;
  if (d_point) {
    double g[3];
    g[2] = (c1 - c0) * inv_voxel_;
    g[1] = (gz * (c10 - c00) + fz * (c11 - c01)) * inv_voxel_;
    g[0] = (gz * (gy * (c[1] - c[0]) + fy * (c[3] - c[2])) +
            fz * (gy * (c[5] - c[4]) + fy * (c[7] - c[6]))) *
           inv_voxel_;
    for (int a = 0; a < 3; ++a) {
      d_point[a] = clamped[a] ? outside[a] / distance : g[a];
    }
  }
  if (d_z) {
    const double w[8] = {gx * gy * gz, fx * gy * gz, gx * fy * gz, fx * fy * gz,
                         gx * gy * fz, fx * gy * fz, gx * fy * fz, fx * fy * fz};
    std::fill(d_z, d_z + nr, 0.0);
    for (int k = 0; k < 8; ++k) {
      const double* row = &table_[size_t(offsets[k]) * stride_ + 1];
      for (int r = 0; r < nr; ++r) d_z[r] += w[k] * row[r];
    }
  }
  return value;
}

}  // namespace

double ShapeLookup::Evaluate(const double* z, const double* point, double* d_point,
                             double* d_z) const {
  switch (num_components_) {
    case 5:
      return EvaluateKernel<5>(grid_, max_corner_, inv_voxel_, table_, 5, z, point, d_point, d_z);
    case 10:
      return EvaluateKernel<10>(grid_, max_corner_, inv_voxel_, table_, 10, z, point, d_point, d_z);
    default:
      return EvaluateKernel<0>(grid_, max_corner_, inv_voxel_, table_, num_components_, z, point,
                               d_point, d_z);
  }
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
  const int64_t d = grid_.NumVoxels();
  std::vector<float> out(static_cast<size_t>(d));
  for (int64_t v = 0; v < d; ++v) {
    const double* row = &table_[size_t(v) * stride_];
    double s = row[0];
    for (int r = 0; r < num_components_; ++r) s += row[1 + r] * z[r];
    out[size_t(v)] = float(s);
  }
  return out;
}

AlignedBox ShapeLookup::InsideBox(const Eigen::VectorXd& z) const {
  const std::vector<float> phi = Dense(z);
  AlignedBox box;
  const Eigen::Vector3i& n = grid_.dims;
  for (int k = 0; k < n.z(); ++k) {
    for (int j = 0; j < n.y(); ++j) {
      for (int i = 0; i < n.x(); ++i) {
        const float v = phi[size_t(grid_.Index(i, j, k))];
        if (!(v < 0.0f)) continue;
        const Eigen::Vector3d p = grid_.Position(i, j, k);
        box.Extend(p);
        // Sub-voxel refinement towards outside neighbours along each axis.
        const int idx[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) {
          for (int s = -1; s <= 1; s += 2) {
            int nb[3] = {i, j, k};
            nb[a] = idx[a] + s;
            if (nb[a] < 0 || nb[a] >= n[a]) continue;
            const float w = phi[size_t(grid_.Index(nb[0], nb[1], nb[2]))];
            if (w < 0.0f) continue;
            Eigen::Vector3d e = p;
            e[a] += s * grid_.voxel_size * double(v) / double(v - w);
            box.Extend(e);
          }
        }
      }
    }
  }
  return box;
}

}  // namespace samp
