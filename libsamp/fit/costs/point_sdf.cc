#include "libsamp/fit/costs/point_sdf.h"

#include <cmath>

namespace samp {

bool PointSdfCost::EvaluateRows(const double* z, const double* pose, int begin, int end, double* residuals,
                                double* jz, int jz_stride, double* jp, int jp_stride) const {
  const int nr = lookup_->num_components();
  const double c = std::cos(pose[3]), s = std::sin(pose[3]);
  const double* phi_z = lookup_->DenseCached(z);
  for (int row = 0; row < end - begin; ++row) {
    const int i = begin + row;
    const double dx = points_[3 * i] - pose[0];
    const double dy = points_[3 * i + 1] - pose[1];
    const double dz = points_[3 * i + 2] - pose[2];
    const double o[3] = {c * dx - s * dz, dy, s * dx + c * dz};
    double g[3];
    double* dz_row = jz ? jz + size_t(row) * jz_stride : nullptr;
    const double phi = lookup_->EvaluateDense(phi_z, o, jp ? g : nullptr, dz_row);
    if (!std::isfinite(phi)) return false;
    double d_psi = 1.0;
    residuals[row] = sqrt_weight_ * Robust(phi * inv_sigmas_[i], &d_psi);  // s_i = phi / sigma_i
    const double f = sqrt_weight_ * d_psi * inv_sigmas_[i];
    WriteJacobianRow(f, c, s, g, o, nr, dz_row, jp ? jp + size_t(row) * jp_stride : nullptr);
  }
  return true;
}

}  // namespace samp
