// The ray-depth data term (samp addition, the fitter's default; docs/fitting.md,
// "Ray distance instead of phi"): the paper's residual (point_sdf.h) with the
// distance measured along each point's viewing ray where stereo noise lies:
//   inside (phi_z(o) < 0):  s_i = -d_i / sigma_i, d_i >= 0 the depth of the
//     point below the first surface crossing towards the camera, c_i = o - d_i u
//     (u the unit ray from the camera, object frame; RayDistance, shape_ray.h);
//   outside, crossing within 5 |phi| away from the camera:  s_i = +d_i / sigma_i;
//   outside without one, the ray meeting the shape before the point (behind
//     the far side):  s_i = -(lambda_i - lambda_s) / sigma_i, lambda_s the first
//     crossing from the camera (FirstCrossing), lambda_i the point's distance;
//   outside, the ray passing the shape (beside the silhouette): the paper's
//     s_i = phi_z(o) / sigma_i.
//   E_data = w / N * sum_i rho(s_i)          (rho: Huber, or the mixture; data_cost.h)
// Stereo noise is along the ray; with noise larger than the car's half width
// the Euclidean phi of points behind the visible surface saturates (and falls
// again towards the far side) while that of points in front grows, which pulls
// the fit towards the camera; the ray depth keeps growing. By implicit
// differentiation of phi_z(c) = 0 (m = -1 / (grad phi(c) . u), grad phi . u <
// -kMinRaySlope), the Jacobians are those of point_sdf.h taken at the crossing
// c (with c in the d/dtheta term) and multiplied by m.
#pragma once

#include <vector>

#include "libsamp/fit/costs/data_cost.h"

namespace samp {

class RayDepthCost : public DataCost {
 public:
  // `lookup` must outlive the cost. points and sigmas have equal, non-zero
  // size; no point at options.camera_in_world.
  RayDepthCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
               const std::vector<double>& sigmas, const DataCostOptions& options)
      : DataCost(lookup, points_in_world, sigmas, options, /*with_rays=*/true) {}

  bool EvaluateRows(const double* z, const double* pose, int begin, int end, double* residuals, double* jz,
                    int jz_stride, double* jp, int jp_stride) const override;

 private:
  // The state of one group of up to kRayBatch points (ray_depth.cc).
  struct Batch;
  // Each point's object-frame position, phi there and ray; the points off the
  // surface queued for RayDistances. False when a phi is not finite.
  bool StartBatch(const PoseFrame& at, const double* pose, Batch* batch) const;
  // The crossings along the rays (RayDistances), and the outside points
  // without one queued for FirstCrossings.
  void FindNearCrossings(const PoseFrame& at, Batch* batch) const;
  // The outside points behind the far side (FirstCrossings).
  void FindFarCrossings(const PoseFrame& at, Batch* batch) const;
  // The residuals and Jacobian rows of the batch's points.
  void WriteRows(const PoseFrame& at, int begin, Batch* batch, double* residuals, double* jz, int jz_stride,
                 double* jp, int jp_stride) const;
};

}  // namespace samp
