#include "libsamp/fit/costs/point_sdf.h"

namespace samp {

bool PointSdfCost::EvaluateRows(const double* z, const double* pose, int begin, int end, double* residuals,
                                double* jz, int jz_stride, double* jp, int jp_stride) const {
  // phi_z at the point is the residual: no refinement.
  return DistanceRows(z, pose, begin, end, residuals, jz, jz_stride, jp, jp_stride);
}

}  // namespace samp
