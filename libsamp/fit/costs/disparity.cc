#include "libsamp/fit/costs/disparity.h"

#include <algorithm>
#include <cmath>

#include "libsamp/core/error.h"
#include "libsamp/fit/costs/shape_ray.h"

namespace samp {

namespace {
constexpr double kMinAxisCosine = 1e-3;
}  // namespace

bool InFrontOfCamera(const Eigen::Vector3d& point, const Eigen::Vector3d& camera_in_world,
                     const Eigen::Vector3d& camera_axis_in_world) {
  const Eigen::Vector3d ray = point - camera_in_world;
  const double length = ray.norm();
  return length > 0.0 && ray.dot(camera_axis_in_world) / length > kMinAxisCosine;
}

DisparityCost::DisparityCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
                             const std::vector<double>& sigmas, const DataCostOptions& options)
    : DataCost(lookup, points_in_world, sigmas, options, /*with_rays=*/true) {
  SAMP_CHECK(options.focal_px > 0.0 && std::isfinite(options.focal_px))
      << "DisparityCost: focal_px must be > 0, got " << options.focal_px;
  SAMP_CHECK(options.silhouette_sigma_px > 0.0) << "DisparityCost: silhouette_sigma_px must be > 0";
  SAMP_CHECK(options.outlier_threshold > 0.0) << "DisparityCost: outlier_threshold must be > 0";
  SAMP_CHECK(std::abs(options.camera_axis_in_world.norm() - 1.0) < 1e-6)
      << "DisparityCost: camera_axis_in_world must be a unit vector";
  const size_t n = points_in_world.size();
  ray_lengths_.resize(n);
  axis_cosines_.resize(n);
  inv_silhouette_sigmas_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d ray = points_in_world[i] - options.camera_in_world;
    ray_lengths_[i] = ray.norm();
    axis_cosines_[i] = ray.dot(options.camera_axis_in_world) / ray_lengths_[i];
    SAMP_CHECK(axis_cosines_[i] > kMinAxisCosine)
        << "DisparityCost: point " << i << " is not in front of the camera (the fit drops such points)";
    const double depth = axis_cosines_[i] * ray_lengths_[i];
    inv_silhouette_sigmas_[i] = options.focal_px / (depth * options.silhouette_sigma_px);
  }
}

RayResidual DisparityCost::Residual(int i, const double* phi_z, const double* o_cam, const double* u, double* m,
                                    double* c, double* g, double* dz_row) const {
  RayResidual out;
  double lambda = 0.0, g_c[3], phi_min = 0.0;
  out.hit = FirstCrossing(*lookup_, phi_z, o_cam, u, &lambda, c, g_c, &phi_min);
  if (out.hit) {
    const double li = ray_lengths_[i], a = axis_cosines_[i], inv_sigma = inv_sigmas_[i];
    double slope = g_c[0] * u[0] + g_c[1] * u[1] + g_c[2] * u[2];
    if (!(slope < -kMinRaySlope)) {
      // Grazing: the crossing moves fast with the parameters; its derivative
      // is taken with the slope clamped (a Gauss-Newton approximation).
      out.grazing = true;
      slope = -kMinRaySlope;
    }
    out.value = a * li * (lambda - li) / lambda * inv_sigma;
    *m = -a * li * li / (lambda * lambda) * inv_sigma / slope;
  } else {
    out.value = phi_min * inv_silhouette_sigmas_[i];
    *m = inv_silhouette_sigmas_[i];
  }
  if (g) {
    for (int k = 0; k < 3; ++k) g[k] = g_c[k];
  }
  if (dz_row) lookup_->EvaluateDense(phi_z, c, nullptr, dz_row);
  return out;
}

bool DisparityCost::EvaluateRows(const double* z, const double* pose, int begin, int end, double* residuals,
                                 double* jz, int jz_stride, double* jp, int jp_stride) const {
  const PoseFrame at = AtPose(z, pose);
  for (int first = begin; first < end; first += kRowChunk) {
    const int n = std::min(kRowChunk, end - first), row0 = first - begin;
    double value[kRowChunk], m[kRowChunk], o[kRowChunk][3], g[kRowChunk][3];
    for (int k = 0; k < n; ++k) {
      double u[3];
      RayInObject(first + k, at.c, at.s, u);
      double* dz_row = jz ? jz + size_t(row0 + k) * jz_stride : nullptr;
      value[k] = Residual(first + k, at.phi_z, at.o_cam, u, &m[k], o[k], jp ? g[k] : nullptr, dz_row).value;
      if (!std::isfinite(value[k])) return false;
    }
    double psi[kRowChunk], d_psi[kRowChunk];
    MixturePsiRows(value, n, mixture_c_, psi, d_psi);
    for (int k = 0; k < n; ++k) {
      residuals[row0 + k] = sqrt_weight_ * psi[k];
      const double f = sqrt_weight_ * d_psi[k] * m[k];
      WriteJacobianRow(f, at.c, at.s, g[k], o[k], at.nr, jz ? jz + size_t(row0 + k) * jz_stride : nullptr,
                       jp ? jp + size_t(row0 + k) * jp_stride : nullptr);
    }
  }
  return true;
}

std::vector<RayResidual> DisparityCost::RayResiduals(const double* z, const double* pose) const {
  const PoseFrame at = AtPose(z, pose);
  std::vector<RayResidual> out(static_cast<size_t>(num_residuals()));
  for (int i = 0; i < num_residuals(); ++i) {
    double u[3];
    RayInObject(i, at.c, at.s, u);
    double m, o[3];
    out[size_t(i)] = Residual(i, at.phi_z, at.o_cam, u, &m, o, nullptr, nullptr);
  }
  return out;
}

}  // namespace samp
