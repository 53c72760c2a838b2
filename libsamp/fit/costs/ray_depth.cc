#include "libsamp/fit/costs/ray_depth.h"

#include <algorithm>
#include <cmath>

#include "libsamp/fit/costs/shape_ray.h"

namespace samp {

bool RayDepthCost::EvaluateRows(const double* z, const double* pose, int begin, int end, double* residuals,
                                double* jz, int jz_stride, double* jp, int jp_stride) const {
  // at.o_cam: the camera centre in the object frame (points behind the far side).
  const PoseFrame at = AtPose(z, pose);
  const int nr = at.nr;
  // Groups of kRayBatch points: the rays of a group are marched in lockstep
  // (RayDistances, FirstCrossings); each ray's result is the single-ray
  // RayDistance's / FirstCrossing's.
  for (int first = begin; first < end; first += kRayBatch) {
    const int count = std::min(kRayBatch, end - first);
    double o[kRayBatch][3], phi[kRayBatch], u[kRayBatch][3];
    RayDistanceQuery near[kRayBatch];
    int near_rows[kRayBatch], num_near = 0;
    for (int b = 0; b < count; ++b) {
      const int i = first + b;
      PointInObject(i, pose, at.c, at.s, o[b]);
      // phi at the point first; its derivatives there only when the residual
      // stays phi (no crossing along the ray): most rows take them at the crossing.
      phi[b] = lookup_->EvaluateDenseValue(at.phi_z, o[b]);
      if (!std::isfinite(phi[b])) return false;
      RayInObject(i, at.c, at.s, u[b]);
      if (phi[b] == 0.0) continue;  // on the surface: phi and its derivatives at the point
      RayDistanceQuery& q = near[num_near];
      for (int a = 0; a < 3; ++a) {
        q.o[a] = o[b][a];
        q.u[a] = u[b][a];
      }
      q.phi_o = phi[b];
      near_rows[num_near++] = b;
    }
    RayDistances(*lookup_, at.phi_z, near, num_near);
    // Outside points without a crossing within reach lie behind the far side
    // when their ray meets the shape before them: minus their depth behind
    // that first crossing, like a point inside.
    bool found[kRayBatch] = {};
    double distance[kRayBatch], crossing[kRayBatch][3], g_crossing[kRayBatch][3], li[kRayBatch];
    FirstCrossingQuery far[kRayBatch];
    int far_rows[kRayBatch], num_far = 0;
    for (int k = 0; k < num_near; ++k) {
      const int b = near_rows[k];
      const RayDistanceQuery& q = near[k];
      if (q.found) {
        found[b] = true;
        distance[b] = q.distance;
        for (int a = 0; a < 3; ++a) {
          crossing[b][a] = q.c[a];
          g_crossing[b][a] = q.g_c[a];
        }
      } else if (phi[b] > 0.0) {
        li[b] = std::sqrt((o[b][0] - at.o_cam[0]) * (o[b][0] - at.o_cam[0]) +
                          (o[b][1] - at.o_cam[1]) * (o[b][1] - at.o_cam[1]) +
                          (o[b][2] - at.o_cam[2]) * (o[b][2] - at.o_cam[2]));
        FirstCrossingQuery& f = far[num_far];
        for (int a = 0; a < 3; ++a) f.u[a] = u[b][a];
        f.max_lambda = li[b];
        far_rows[num_far++] = b;
      }
    }
    FirstCrossings(*lookup_, at.phi_z, at.o_cam, far, num_far);
    for (int k = 0; k < num_far; ++k) {
      const int b = far_rows[k];
      const FirstCrossingQuery& f = far[k];
      if (!(f.hit && f.lambda < li[b] &&
            f.g_c[0] * u[b][0] + f.g_c[1] * u[b][1] + f.g_c[2] * u[b][2] < -kMinRaySlope)) {
        continue;
      }
      found[b] = true;
      distance[b] = li[b] - f.lambda;
      phi[b] = -phi[b];  // behind the visible surface: signed like a point inside
      for (int a = 0; a < 3; ++a) {
        crossing[b][a] = f.c[a];
        g_crossing[b][a] = f.g_c[a];
      }
    }
    for (int b = 0; b < count; ++b) {
      const int i = first + b, row = i - begin;
      double* dz_row = jz ? jz + size_t(row) * jz_stride : nullptr;
      double g[3];
      double value = phi[b];
      if (found[b]) {
        // phi_eff = sign(phi) distance; by implicit differentiation of
        // phi(crossing) = 0 its derivatives are those of phi at the crossing
        // times m = -1 / (grad phi . u) (grad phi . u < -kMinRaySlope).
        const double m = -1.0 / (g_crossing[b][0] * u[b][0] + g_crossing[b][1] * u[b][1] +
                                 g_crossing[b][2] * u[b][2]);
        for (int a = 0; a < 3; ++a) {
          o[b][a] = crossing[b][a];
          g[a] = g_crossing[b][a] * m;
        }
        if (dz_row) {
          lookup_->EvaluateDense(at.phi_z, crossing[b], nullptr, dz_row);
          for (int r = 0; r < nr; ++r) dz_row[r] *= m;
        }
        value = phi[b] < 0.0 ? -distance[b] : distance[b];
      } else if (jp || dz_row) {
        lookup_->EvaluateDense(at.phi_z, o[b], jp ? g : nullptr, dz_row);
      }
      WriteDistanceRow(i, value, at.c, at.s, g, o[b], nr, &residuals[row], dz_row,
                       jp ? jp + size_t(row) * jp_stride : nullptr);
    }
  }
  return true;
}

}  // namespace samp
