// SDF data term of one frame of a track (SAMP Section 3.2), ONE Ceres cost
// block per frame with analytic Jacobians.
//
// For the N observed points x_i (world) with depth noise sigma_i, the pose
// (t, theta) and the shape code z:
//   s_i = phi_z(R_y(theta)^T (x_i - t)) / sigma_i
//   E_data = w / N * sum_i rho(s_i),   rho = Huber with threshold k:
//            rho(s) = s^2 (|s| <= k),  2 k |s| - k^2 (|s| > k)
// Ceres applies a LossFunction to a whole block, so the robustifier lives
// inside the block: residual r_i = sqrt(w / N) psi(s_i) with
//   psi(s) = s (|s| <= k),  sign(s) sqrt(2 k |s| - k^2) (|s| > k),
// hence sum_i r_i^2 = E_data exactly; psi is C^1 (psi' = k / |psi| outside).
// w = 1 / T weights a frame of a T-frame track. phi_z is the trilinear
// lookup of ShapeLookup (outside the grid: value grows with the distance to
// the grid box, gradient points back). Jacobians:
//   d r_i / d z     = sqrt(w/N) psi'(s_i) / sigma_i * d phi / d z  (trilinear weights on W)
//   d r_i / d t     = -sqrt(w/N) psi'(s_i) / sigma_i * (R grad phi)^T
//   d r_i / d theta =  sqrt(w/N) psi'(s_i) / sigma_i * grad phi . (-o_z, 0, o_x)
// where o = the point in the object frame.
// Parameter blocks: z (R values), pose (tx, ty, tz, theta).
//
// Option ray_depth_inside (SdfCostOptions): for a point inside the shape
// (phi < 0) the distance is measured along the viewing ray instead: s_i =
// -d_i / sigma_i, d_i >= 0 the depth of the point below the first surface
// crossing towards the camera, c_i = o - d_i u (u the unit ray from the camera
// in the object frame), found by sphere tracing on phi_z and refined by Newton
// steps. Stereo noise is along the ray; with noise larger than the car's half
// width the Euclidean phi of points behind the visible surface saturates (and
// falls again towards the far side) while that of points in front grows, which
// pulls the fit towards the camera; the ray depth keeps growing. By implicit
// differentiation of phi_z(c) = 0 (m = -1 / (grad phi(c) . u), clamped to
// <= 1 / 0.2), the Jacobians are those of phi above taken at c (with c in the
// d/dtheta term) and multiplied by m.
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <cmath>
#include <mutex>
#include <vector>

#include "libsamp/model/shape_lookup.h"

namespace samp {

struct SdfCostOptions {
  double huber_threshold = 1.0;  // k, in units of sigma
  double weight = 1.0;           // w (1 / T for one frame of a T-frame track)
  // Inside points by their depth along the viewing ray from camera_in_world
  // (see above); off: phi everywhere, as the paper.
  bool ray_depth_inside = false;
  Eigen::Vector3d camera_in_world = Eigen::Vector3d::Zero();
};

class SdfCost : public ceres::CostFunction {
 public:
  // `lookup` must outlive the cost. points and sigmas have equal, non-zero size.
  SdfCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
          const std::vector<double>& sigmas, const SdfCostOptions& options);
  SdfCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
          const std::vector<double>& sigmas, double huber_threshold, double weight)
      : SdfCost(lookup, points_in_world, sigmas, SdfCostOptions{huber_threshold, weight}) {}

  static ceres::CostFunction* Create(const ShapeLookup* lookup,
                                     const std::vector<Eigen::Vector3d>& points_in_world,
                                     const std::vector<double>& sigmas, const SdfCostOptions& options) {
    return new SdfCost(lookup, points_in_world, sigmas, options);
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  // Evaluate() for the points [begin, end) with the Jacobian rows written
  // with strides: residual of point begin + i at residuals[i], its row of
  // d/dz (R values) at jz + i jz_stride, of d/d(t, theta) (4 values) at
  // jp + i jp_stride; null jz / jp skip them. phi_z comes from the lookup's
  // per-thread dense grid of z (ShapeLookup::DenseCached).
  bool EvaluateRows(const double* z, const double* pose, int begin, int end, double* residuals, double* jz,
                    int jz_stride, double* jp, int jp_stride) const;

  // The Huber robustifier psi and its derivative (exposed for tests).
  static double Psi(double s, double k, double* d_psi) {
    const double a = std::abs(s);
    if (a <= k) {
      if (d_psi) *d_psi = 1.0;
      return s;
    }
    const double root = std::sqrt(2.0 * k * a - k * k);
    if (d_psi) *d_psi = k / root;
    return s > 0.0 ? root : -root;
  }

 private:
  // Distance from o along the object-frame viewing ray u to the surface:
  // towards the camera (-u) from inside (phi_o < 0), away from it from
  // outside; the crossing c and grad phi there. False when none is found
  // within kMaxRayRatio |phi_o| or the ray grazes the surface.
  bool RayDistance(const double* phi_z, const double* o, double phi_o, const double* u, double* distance,
                   double* c, double* g_c) const;

  const ShapeLookup* lookup_;
  std::vector<double> points_;  // 3 per point
  std::vector<double> rays_;    // 3 per point (unit, world), ray_depth_inside only
  std::vector<double> inv_sigmas_;  // 1 / sigma_i
  double huber_ = 1.0;
  double sqrt_weight_ = 1.0;    // sqrt(w / N)
};

// The same data term compressed to R + 5 residuals with identical cost,
// gradient and Gauss-Newton Hessian, so Ceres' linear algebra works on a
// (R + 4)-row block instead of an N-row one (the per-point work stays):
// with J, r the N-row Jacobian and residuals of SdfCost at the current
// parameters, H = J^T J + eps I = L L^T (Cholesky, eps = 1e-12 trace(H)),
//   residuals  = (L^-1 J^T r, sqrt(max(0, |r|^2 - |L^-1 J^T r|^2)))
//   Jacobian   = (L^T; 0)
// => |residuals|^2 = |r|^2 (the cost), Jacobian^T residuals = J^T r (the
// gradient), Jacobian^T Jacobian = H (the Gauss-Newton matrix), and
// |Jacobian d + residuals|^2 = |J d + r|^2 for every step d, so
// Levenberg-Marquardt takes exactly the steps of the uncompressed problem.
// The returned Jacobian is NOT the derivative of the returned residuals
// (those depend on the linearisation point); tests compare cost, gradient
// and J^T J with SdfCost instead of numeric differentiation.
// Eager linearisation: every evaluation, also a cost-only one, computes the
// Jacobian and keeps the result for its parameters. Levenberg-Marquardt
// evaluates the cost of each trial step and then, when the step is accepted
// (almost always with this data term), the Jacobian at the same parameters:
// that second call is a copy. One Evaluate at a time per block (a mutex).
class CompressedSdfCost : public ceres::CostFunction {
 public:
  CompressedSdfCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
                    const std::vector<double>& sigmas, const SdfCostOptions& options);
  CompressedSdfCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
                    const std::vector<double>& sigmas, double huber_threshold, double weight)
      : CompressedSdfCost(lookup, points_in_world, sigmas, SdfCostOptions{huber_threshold, weight}) {}

  static ceres::CostFunction* Create(const ShapeLookup* lookup,
                                     const std::vector<Eigen::Vector3d>& points_in_world,
                                     const std::vector<double>& sigmas, const SdfCostOptions& options) {
    return new CompressedSdfCost(lookup, points_in_world, sigmas, options);
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  // Residuals and Jacobians at (z, pose) into the cache; false when not finite.
  bool Linearize(const double* z, const double* pose) const;

  SdfCost full_;
  int num_components_;
  mutable std::mutex cache_mutex_;
  mutable bool cache_valid_ = false;
  mutable std::vector<double> cache_parameters_;  // z, then pose
  mutable std::vector<double> cache_residuals_;   // R + 5
  mutable std::vector<double> cache_jz_, cache_jp_;  // (R + 5) x R, (R + 5) x 4, row-major
};

}  // namespace samp
