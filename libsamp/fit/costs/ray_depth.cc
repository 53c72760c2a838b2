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
    if (FirstCrossing(*lookup_, phi_z, o_cam, u, &lambda, crossing, g_crossing, &phi_min, /*refine_miss=*/false,
                      /*max_lambda=*/li) &&
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
  const PoseFrame at = AtPose(z, pose);
  for (int row = 0; row < end - begin; ++row) {
    const int i = begin + row;
    double o[3], g[3];
    PointInObject(i, pose, at.c, at.s, o);
    double* dz_row = jz ? jz + size_t(row) * jz_stride : nullptr;
    // phi at the point first; its derivatives there only when the residual
    // stays phi (no crossing along the ray): most rows take them at the crossing.
    double phi = lookup_->EvaluateDense(at.phi_z, o, nullptr, nullptr);
    if (!std::isfinite(phi)) return false;
    bool along_ray = false;
    if (phi != 0.0) {
      double u[3];
      RayInObject(i, at.c, at.s, u);
      along_ray = ToRayDistance(at.phi_z, at.o_cam, u, &phi, o, g, dz_row);
    }
    if (!along_ray && (jp || dz_row)) lookup_->EvaluateDense(at.phi_z, o, jp ? g : nullptr, dz_row);
    WriteDistanceRow(i, phi, at.c, at.s, g, o, at.nr, &residuals[row], dz_row,
                     jp ? jp + size_t(row) * jp_stride : nullptr);
  }
  return true;
}

}  // namespace samp
