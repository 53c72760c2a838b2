#include "libsamp/fit/costs/ray_depth.h"

#include <algorithm>
#include <cmath>

#include "libsamp/fit/costs/shape_ray.h"

namespace samp {

// Points [first, first + count), indexed by b; their rays are marched in
// lockstep (RayDistances, FirstCrossings).
struct RayDepthCost::Batch {
  int first = 0, count = 0;
  double o[kRayBatch][3], phi[kRayBatch], u[kRayBatch][3];
  // The cell of o (o_in_cell: o lies inside the grid box), for the
  // derivatives at o of the rows without a crossing.
  ShapeLookup::DenseCell o_cell[kRayBatch];
  bool o_in_cell[kRayBatch];
  // The points off the surface (RayDistances): query k is point near_rows[k].
  RayDistanceQuery near[kRayBatch];
  int near_rows[kRayBatch], num_near = 0;
  // A crossing found: the distance to it, the crossing and grad phi there,
  // its cell (crossing_in_cell: inside the grid box) for d/dz there.
  bool found[kRayBatch] = {};
  double distance[kRayBatch], crossing[kRayBatch][3], g_crossing[kRayBatch][3];
  ShapeLookup::DenseCell crossing_cell[kRayBatch];
  bool crossing_in_cell[kRayBatch];
  // Outside points without a crossing within reach (FirstCrossings): query k
  // is point far_rows[k], li its distance from the camera.
  double li[kRayBatch];
  FirstCrossingQuery far[kRayBatch];
  int far_rows[kRayBatch], num_far = 0;
};

bool RayDepthCost::EvaluateRows(const double* z, const double* pose, int begin, int end, double* residuals,
                                double* jz, int jz_stride, double* jp, int jp_stride) const {
  // at.o_cam: the camera centre in the object frame (points behind the far side).
  const PoseFrame at = AtPose(z, pose);
  // Groups of kRayBatch points: the rays of a group are marched in lockstep
  // (RayDistances, FirstCrossings); each ray's result is the single-ray
  // RayDistance's / FirstCrossing's.
  for (int first = begin; first < end; first += kRayBatch) {
    Batch batch;
    batch.first = first;
    batch.count = std::min(kRayBatch, end - first);
    if (!StartBatch(at, pose, &batch)) return false;
    FindNearCrossings(at, &batch);
    FindFarCrossings(at, &batch);
    WriteRows(at, begin, &batch, residuals, jz, jz_stride, jp, jp_stride);
  }
  return true;
}

bool RayDepthCost::StartBatch(const PoseFrame& at, const double* pose, Batch* batch) const {
  Batch& rays = *batch;
  // phi at the points first; its derivatives there only when the residual
  // stays phi (no crossing along the ray): most rows take them at the crossing.
  // Several at a time (DenseValuePair::EvaluateCells: their cells and phi,
  // bit for bit).
  double x[kRayBatch], y[kRayBatch], z[kRayBatch];
  for (int b = 0; b < rays.count; ++b) {
    PointInObject(rays.first + b, pose, at.c, at.s, rays.o[b]);
    x[b] = rays.o[b][0], y[b] = rays.o[b][1], z[b] = rays.o[b][2];
  }
  const ShapeLookup::DenseValuePair pair(*lookup_, at.phi_z);
  pair.EvaluateCells(rays.count, x, y, z, rays.o_cell, rays.o_in_cell, rays.phi, nullptr);
  for (int b = 0; b < rays.count; ++b) {
    const int i = rays.first + b;
    if (!std::isfinite(rays.phi[b])) return false;
    RayInObject(i, at.c, at.s, rays.u[b]);
    if (rays.phi[b] == 0.0) continue;  // on the surface: phi and its derivatives at the point
    RayDistanceQuery& q = rays.near[rays.num_near];
    for (int a = 0; a < 3; ++a) {
      q.o[a] = rays.o[b][a];
      q.u[a] = rays.u[b][a];
    }
    q.phi_o = rays.phi[b];
    rays.near_rows[rays.num_near++] = b;
  }
  return true;
}

void RayDepthCost::FindNearCrossings(const PoseFrame& at, Batch* batch) const {
  Batch& rays = *batch;
  RayDistances(*lookup_, at.phi_z, rays.near, rays.num_near);
  // Outside points without a crossing within reach lie behind the far side
  // when their ray meets the shape before them: minus their depth behind
  // that first crossing, like a point inside.
  for (int k = 0; k < rays.num_near; ++k) {
    const int b = rays.near_rows[k];
    const RayDistanceQuery& q = rays.near[k];
    if (q.found) {
      rays.found[b] = true;
      rays.distance[b] = q.distance;
      for (int a = 0; a < 3; ++a) {
        rays.crossing[b][a] = q.c[a];
        rays.g_crossing[b][a] = q.g_c[a];
      }
      rays.crossing_cell[b] = q.cell;
      rays.crossing_in_cell[b] = q.in_cell;
    } else if (rays.phi[b] > 0.0) {
      const double* o = rays.o[b];
      rays.li[b] = std::sqrt((o[0] - at.o_cam[0]) * (o[0] - at.o_cam[0]) +
                          (o[1] - at.o_cam[1]) * (o[1] - at.o_cam[1]) +
                          (o[2] - at.o_cam[2]) * (o[2] - at.o_cam[2]));
      FirstCrossingQuery& f = rays.far[rays.num_far];
      for (int a = 0; a < 3; ++a) f.u[a] = rays.u[b][a];
      f.max_lambda = rays.li[b];
      rays.far_rows[rays.num_far++] = b;
    }
  }
}

void RayDepthCost::FindFarCrossings(const PoseFrame& at, Batch* batch) const {
  Batch& rays = *batch;
  FirstCrossings(*lookup_, at.phi_z, at.o_cam, rays.far, rays.num_far);
  for (int k = 0; k < rays.num_far; ++k) {
    const int b = rays.far_rows[k];
    const FirstCrossingQuery& f = rays.far[k];
    const double* u = rays.u[b];
    if (!(f.hit && f.lambda < rays.li[b] && f.g_c[0] * u[0] + f.g_c[1] * u[1] + f.g_c[2] * u[2] < -kMinRaySlope)) {
      continue;
    }
    rays.found[b] = true;
    rays.distance[b] = rays.li[b] - f.lambda;
    rays.phi[b] = -rays.phi[b];  // behind the visible surface: signed like a point inside
    for (int a = 0; a < 3; ++a) {
      rays.crossing[b][a] = f.c[a];
      rays.g_crossing[b][a] = f.g_c[a];
    }
    rays.crossing_cell[b] = f.cell;
    rays.crossing_in_cell[b] = f.in_cell;
  }
}

void RayDepthCost::WriteRows(const PoseFrame& at, int begin, Batch* batch, double* residuals, double* jz,
                             int jz_stride, double* jp, int jp_stride) const {
  static_assert(kRayBatch <= kRowChunk, "a batch's rows are written at once");
  Batch& rays = *batch;
  const int row0 = rays.first - begin;
  double value[kRayBatch], g[kRayBatch][3];
  for (int b = 0; b < rays.count; ++b) {
    double* dz_row = jz ? jz + size_t(row0 + b) * jz_stride : nullptr;
    value[b] = rays.phi[b];
    if (rays.found[b]) {
      // phi_eff = sign(phi) distance; by implicit differentiation of
      // phi(crossing) = 0 its derivatives are those of phi at the crossing
      // times m = -1 / (grad phi . u) (grad phi . u < -kMinRaySlope).
      const double* g_c = rays.g_crossing[b];
      const double m = -1.0 / (g_c[0] * rays.u[b][0] + g_c[1] * rays.u[b][1] + g_c[2] * rays.u[b][2]);
      for (int a = 0; a < 3; ++a) {
        rays.o[b][a] = rays.crossing[b][a];
        g[b][a] = g_c[a] * m;
      }
      if (dz_row) {
        // The crossing's cell from its last Newton step (EvaluateDense's d/dz, bit for bit).
        if (rays.crossing_in_cell[b]) {
          lookup_->CodeGradientAt(rays.crossing_cell[b], dz_row);
        } else {
          lookup_->EvaluateDense(at.phi_z, rays.crossing[b], nullptr, dz_row);
        }
        for (int r = 0; r < at.nr; ++r) dz_row[r] *= m;
      }
      value[b] = rays.phi[b] < 0.0 ? -rays.distance[b] : rays.distance[b];
    } else if (rays.o_in_cell[b]) {
      // The point's cell from StartBatch (EvaluateDense's derivatives, bit for bit).
      if (jp) lookup_->DenseAt(at.phi_z, rays.o_cell[b], g[b]);
      if (dz_row) lookup_->CodeGradientAt(rays.o_cell[b], dz_row);
    } else if (jp || dz_row) {
      lookup_->EvaluateDense(at.phi_z, rays.o[b], jp ? g[b] : nullptr, dz_row);
    }
  }
  WriteDistanceRows(rays.first, rays.count, value, g, rays.o, at.c, at.s, at.nr, residuals + row0,
                    jz ? jz + size_t(row0) * jz_stride : nullptr, jz_stride,
                    jp ? jp + size_t(row0) * jp_stride : nullptr, jp_stride);
}

}  // namespace samp
