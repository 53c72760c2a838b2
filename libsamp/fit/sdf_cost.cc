#include "libsamp/fit/sdf_cost.h"

#include <cmath>

#include "libsamp/core/error.h"

namespace samp {

SdfCost::SdfCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
                 const std::vector<double>& sigmas, double huber_threshold, double weight)
    : lookup_(lookup), huber_(huber_threshold) {
  SAMP_CHECK(lookup != nullptr) << "SdfCost: null shape lookup";
  SAMP_CHECK(!points_in_world.empty()) << "SdfCost: no points";
  SAMP_CHECK(points_in_world.size() == sigmas.size())
      << "SdfCost: " << points_in_world.size() << " points but " << sigmas.size() << " sigmas";
  SAMP_CHECK(huber_threshold > 0.0) << "SdfCost: Huber threshold must be > 0";
  SAMP_CHECK(weight > 0.0) << "SdfCost: weight must be > 0";
  const size_t n = points_in_world.size();
  sqrt_weight_ = std::sqrt(weight / double(n));
  points_.resize(3 * n);
  inv_sigmas_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    SAMP_CHECK(points_in_world[i].allFinite()) << "SdfCost: point " << i << " is not finite";
    SAMP_CHECK(sigmas[i] > 0.0 && std::isfinite(sigmas[i]))
        << "SdfCost: sigma of point " << i << " must be > 0, got " << sigmas[i];
    for (int a = 0; a < 3; ++a) points_[3 * i + a] = points_in_world[i][a];
    inv_sigmas_[i] = 1.0 / sigmas[i];
  }
  set_num_residuals(int(n));
  mutable_parameter_block_sizes()->push_back(lookup->num_components());
  mutable_parameter_block_sizes()->push_back(4);
}

double SdfCost::Psi(double s, double k, double* d_psi) {
  const double a = std::abs(s);
  if (a <= k) {
    if (d_psi) *d_psi = 1.0;
    return s;
  }
  const double root = std::sqrt(2.0 * k * a - k * k);
  if (d_psi) *d_psi = k / root;
  return s > 0.0 ? root : -root;
}

bool SdfCost::Evaluate(double const* const* parameters, double* residuals,
                       double** jacobians) const {
  const double* z = parameters[0];
  const double* pose = parameters[1];
  const int nr = lookup_->num_components();
  const int n = num_residuals();
  const double c = std::cos(pose[3]), s = std::sin(pose[3]);
  double* jz = jacobians ? jacobians[0] : nullptr;
  double* jp = jacobians ? jacobians[1] : nullptr;
  const bool need_point_gradient = jp != nullptr;
  for (int i = 0; i < n; ++i) {
    const double dx = points_[3 * i] - pose[0];
    const double dy = points_[3 * i + 1] - pose[1];
    const double dz = points_[3 * i + 2] - pose[2];
    const double o[3] = {c * dx - s * dz, dy, s * dx + c * dz};
    double g[3];
    double* dz_row = jz ? jz + size_t(i) * nr : nullptr;
    const double phi = lookup_->Evaluate(z, o, need_point_gradient ? g : nullptr, dz_row);
    if (!std::isfinite(phi)) return false;
    double d_psi = 1.0;
    const double scaled = phi * inv_sigmas_[i];  // s_i = phi / sigma_i
    residuals[i] = sqrt_weight_ * Psi(scaled, huber_, &d_psi);
    const double f = sqrt_weight_ * d_psi * inv_sigmas_[i];
    if (dz_row) {
      for (int r = 0; r < nr; ++r) dz_row[r] *= f;
    }
    if (jp) {
      double* row = jp + size_t(i) * 4;
      // R grad = (c g0 + s g2, g1, -s g0 + c g2).
      row[0] = -f * (c * g[0] + s * g[2]);
      row[1] = -f * g[1];
      row[2] = -f * (-s * g[0] + c * g[2]);
      row[3] = f * (-g[0] * o[2] + g[2] * o[0]);
    }
  }
  return true;
}

}  // namespace samp
