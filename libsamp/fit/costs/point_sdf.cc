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
    double o[3], g[3];
    PointInObject(i, pose, c, s, o);
    double* dz_row = jz ? jz + size_t(row) * jz_stride : nullptr;
    const double phi = lookup_->EvaluateDense(phi_z, o, jp ? g : nullptr, dz_row);
    if (!std::isfinite(phi)) return false;
    WriteDistanceRow(i, phi, c, s, g, o, nr, &residuals[row], dz_row,
                     jp ? jp + size_t(row) * jp_stride : nullptr);
  }
  return true;
}

}  // namespace samp
