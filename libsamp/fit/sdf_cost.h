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
// d/dtheta term) and multiplied by m. An outside point whose ray (away from
// the camera) finds no crossing within 5 |phi|: when its ray meets the shape
// before it (the point lies behind the far side), s_i = -(lambda_i -
// lambda_s) / sigma_i with lambda_s the first crossing from the camera (as
// the disparity term finds it), derivatives as for a point inside with c the
// first crossing; when the ray passes the shape (beside the silhouette), the
// Euclidean phi (the paper's residual). Before 2026-12-02 both counted 5 phi,
// which pulled shapes towards clutter beside the car and let points behind
// the far side cost less than their depth (docs/fitting.md, "Known bias").
//
// Data term kDisparity (the fitter's default, docs/fitting.md): every point
// is compared with the shape's visible surface on its own viewing ray, in
// disparity. The ray from the camera centre through the point, in the object
// frame c(lambda) = o_cam + lambda u (u unit, lambda the distance from the
// camera), enters the grid box at lambda_in; sphere tracing from there finds
// the first crossing lambda_s (phi_z(c(lambda_s)) = 0, phi < 0 behind it):
// the surface the camera sees on that pixel. With the point's distance
// lambda_i, a_i = u . (optical axis) (depth z = a lambda) and sigma_i the
// depth noise sigma_d = z^2 sigma_disp / (b f):
//   hit:  s_i = b f (1/z_i - 1/z_s) / sigma_disp
//             = a_i lambda_i (lambda_s - lambda_i) / (lambda_s sigma_i)
// the disparity error in units of sigma_disp (b f cancels): homoscedastic,
// unbiased for stereo noise, positive in front of the surface, negative
// behind it (inside the car or beyond). Derivatives by implicit
// differentiation of phi_z(c(lambda_s)) = 0:
//   d lambda_s = -(d phi at c, lambda fixed) / (grad phi(c) . u)
//   d s_i / d lambda_s = a_i lambda_i^2 / (lambda_s^2 sigma_i)
// and "d phi at c, lambda fixed" is the point Jacobian above taken at the
// world point of c. At a grazing crossing (grad phi . u > -0.05) the slope is
// clamped to -0.05 in the derivative (Gauss-Newton approximation).
//   miss: the ray passes the shape. s_i = d_i / sigma_sil,i with d_i =
// min_lambda phi_z(c(lambda)) over the grid box (the ray's clearance of the
// silhouette; lambda* by the sampled minimum refined with a parabola) and
// sigma_sil,i = z_i silhouette_sigma_px / f (the silhouette's image-space
// uncertainty). By the envelope theorem d d_i = d phi at c(lambda*),
// lambda* fixed.
// Robust likelihood: the point is the surface's disparity plus Gaussian noise
// with probability 1 - eps, or belongs to something else (background behind
// the car, an occluder in front, a wrong match) with a flat density; the
// negative log-likelihood, shifted to 0 at s = 0, is
//   rho(s) = -2 log((exp(-s^2/2) + c) / (1 + c)),  c = exp(-s_0^2 / 2)
// (s_0 = outlier_threshold: where the two components are equally likely;
// rho -> rho_max = -2 log(c / (1 + c)) beyond it, so clutter and occluders
// add a constant). Residual r_i = sqrt(w / N) psi(s_i), psi = sign(s) sqrt(rho).
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <cmath>
#include <mutex>
#include <string>
#include <vector>

#include "libsamp/model/shape_lookup.h"

namespace samp {

// Which residual a point contributes (see above).
enum class DataTerm {
  kPaper,      // phi_z at the point / sigma_d, Huber (SAMP Section 3.2)
  kRayDepth,   // distance along the viewing ray to the surface, Huber ("ray_depth_inside")
  kDisparity,  // disparity of the point vs that of the visible surface on its ray, robust mixture
};
const char* DataTermName(DataTerm term);  // "paper", "ray-depth", "disparity"
// Throws samp::Error for an unknown name.
DataTerm ParseDataTerm(const std::string& name);

struct SdfCostOptions {
  double huber_threshold = 1.0;  // k, in units of sigma (kPaper, kRayDepth)
  double weight = 1.0;           // w: the block's cost is w times the mean of rho over its points
  DataTerm term = DataTerm::kPaper;
  // Camera centre of the frame (kRayDepth, kDisparity) and its optical axis
  // (unit, world; kDisparity: depth z = distance along the ray times u . axis).
  Eigen::Vector3d camera_in_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d camera_axis_in_world = Eigen::Vector3d::UnitZ();
  // kDisparity: focal length (px) and silhouette uncertainty (px) of rays
  // that miss the shape; s_0 of the mixture, in units of sigma.
  double focal_px = 0.0;
  double silhouette_sigma_px = 2.0;
  double outlier_threshold = 3.0;
  // kPaper / kRayDepth: the robust Gaussian + uniform mixture of kDisparity
  // (threshold outlier_threshold) instead of Huber: a point of something else
  // (clutter, background, a neighbouring car) adds a bounded cost and no pull.
  bool mixture_loss = false;
};

// Per-point classification of the kDisparity term (EM association, reports).
struct RayResidual {
  bool hit = false;     // the ray meets the shape
  bool grazing = false; // ... at a grazing angle (derivative with a clamped slope)
  double value = 0.0;   // s_i before the robustifier (hit: disparity error / sigma_disp; miss: clearance / sigma_sil)
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

  // kDisparity: s_i of every point at (z, pose), before the robustifier.
  std::vector<RayResidual> RayResiduals(const double* z, const double* pose) const;

  // The mixture robustifier of kDisparity: psi(s) = sign(s) sqrt(rho(s)),
  // rho(s) = -2 log((exp(-s^2/2) + c) / (1 + c)), c = exp(-s0^2/2); and d psi / ds.
  static double MixturePsi(double s, double s0, double* d_psi);

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

  // kDisparity: the first crossing of the ray o_cam + lambda u (object frame)
  // with the surface, from the grid box entry. Hit: *lambda = lambda_s, c and
  // grad phi at c, true. Miss: *lambda = lambda* of the smallest phi along
  // the ray (c, g_c there, *phi_min = phi(c)), false; without refine_miss a
  // miss returns false at once (c, g_c, *phi_min unset).
  bool FirstCrossing(const double* phi_z, const double* o_cam, const double* u, double* lambda, double* c,
                     double* g_c, double* phi_min, bool refine_miss = true) const;
  // kDisparity residual of point i: s_i, the factor m with d s_i = m (d phi
  // at c), c (object frame) and, when g / dz_row are given, grad phi and
  // d phi / dz at c.
  RayResidual DisparityResidual(int i, const double* phi_z, const double* o_cam, const double* u, double* m,
                                double* c, double* g, double* dz_row) const;

  const ShapeLookup* lookup_;
  DataTerm term_ = DataTerm::kPaper;
  std::vector<double> points_;  // 3 per point
  std::vector<double> rays_;    // 3 per point (unit, world), kRayDepth and kDisparity
  std::vector<double> ray_lengths_;  // lambda_i, kDisparity
  std::vector<double> axis_cosines_; // a_i = u . optical axis, kDisparity
  std::vector<double> inv_silhouette_sigmas_;  // 1 / sigma_sil,i, kDisparity
  Eigen::Vector3d camera_ = Eigen::Vector3d::Zero();
  double outlier_threshold_ = 3.0;
  std::vector<double> inv_sigmas_;  // 1 / sigma_i
  double huber_ = 1.0;
  bool mixture_ = false;  // SdfCostOptions::mixture_loss (kPaper, kRayDepth)
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
