#include "libsamp/fit/costs/ray_depth.h"

#include <cmath>

#include "libsamp/fit/costs/shape_ray.h"

namespace samp {

bool RayDepthCost::ToRayDistance(const double* phi_z, const double* o_cam, const double* u, double* phi, double* o,
                                 double* g, double* dz_row) const {
  const int nr = lookup_->num_components();
  double distance, crossing[3], g_crossing[3];
  bool found = RayDistance(*lookup_, phi_z, o, *phi, u, &distance, crossing, g_crossing);
  if (!found && *phi > 0.0) {
    // An outside point without a crossing within reach lies behind the far
    // side when its ray meets the shape before it: minus its depth behind that
    // first crossing, like a point inside.
    double lambda, phi_min;
    const double li = std::sqrt((o[0] - o_cam[0]) * (o[0] - o_cam[0]) + (o[1] - o_cam[1]) * (o[1] - o_cam[1]) +
                                (o[2] - o_cam[2]) * (o[2] - o_cam[2]));
    if (FirstCrossing(*lookup_, phi_z, o_cam, u, &lambda, crossing, g_crossing, &phi_min, /*refine_miss=*/false) &&
        lambda < li && g_crossing[0] * u[0] + g_crossing[1] * u[1] + g_crossing[2] * u[2] < -kMinRaySlope) {
      found = true;
      distance = li - lambda;
      *phi = -*phi;  // behind the visible surface: signed like a point inside
    }
  }
  if (!found) return false;
  // phi_eff = sign(phi) distance; by implicit differentiation of
  // phi(crossing) = 0 its derivatives are those of phi at the crossing times
  // m = -1 / (grad phi . u) (grad phi . u < -kMinRaySlope).
  const double m = -1.0 / (g_crossing[0] * u[0] + g_crossing[1] * u[1] + g_crossing[2] * u[2]);
  for (int a = 0; a < 3; ++a) {
    o[a] = crossing[a];
    g[a] = g_crossing[a];
  }
  if (dz_row) lookup_->EvaluateDense(phi_z, crossing, nullptr, dz_row);
  *phi = *phi < 0.0 ? -distance : distance;
  for (int a = 0; a < 3; ++a) g[a] *= m;
  if (dz_row) {
    for (int r = 0; r < nr; ++r) dz_row[r] *= m;
  }
  return true;
}

bool RayDepthCost::EvaluateRows(const double* z, const double* pose, int begin, int end, double* residuals,
                                double* jz, int jz_stride, double* jp, int jp_stride) const {
  // at.o_cam: the camera centre in the object frame (points behind the far side).
  return DistanceRows(z, pose, begin, end, residuals, jz, jz_stride, jp, jp_stride,
                      [this](int i, const PoseFrame& at, double* phi, double* o, double* g, double* dz_row) {
                        if (*phi == 0.0) return;  // phi, g, dz_row stay phi's at o
                        double u[3];
                        RayInObject(i, at.c, at.s, u);
                        ToRayDistance(at.phi_z, at.o_cam, u, phi, o, g, dz_row);
                      });
}

}  // namespace samp
