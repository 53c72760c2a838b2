#include "libsamp/fit/costs/point_sdf.h"

#include <cmath>

namespace samp {

bool PointSdfCost::EvaluateRows(const double* z, const double* pose, int begin, int end, double* residuals,
                                double* jz, int jz_stride, double* jp, int jp_stride) const {
  const PoseFrame at = AtPose(z, pose);
  for (int row = 0; row < end - begin; ++row) {
    const int i = begin + row;
    double o[3], g[3];
    PointInObject(i, pose, at.c, at.s, o);
    double* dz_row = jz ? jz + size_t(row) * jz_stride : nullptr;
    const double phi = lookup_->EvaluateDense(at.phi_z, o, jp ? g : nullptr, dz_row);
    if (!std::isfinite(phi)) return false;
    WriteDistanceRow(i, phi, at.c, at.s, g, o, at.nr, &residuals[row], dz_row,
                     jp ? jp + size_t(row) * jp_stride : nullptr);
  }
  return true;
}

}  // namespace samp
