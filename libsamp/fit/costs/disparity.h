// The disparity data term (samp addition; docs/fitting.md, "Disparity along
// the viewing ray"): every point is compared with the shape's visible surface
// on its own viewing ray, in disparity. The ray from the camera centre through
// the point, in the object frame c(lambda) = o_cam + lambda u (u unit, lambda
// the distance from the camera), meets the surface first at lambda_s
// (FirstCrossing, shape_ray.h): the surface the camera sees on that pixel.
// With the point's distance lambda_i, a_i = u . (optical axis) (depth z =
// a lambda) and sigma_i the depth noise sigma_d = z^2 sigma_disp / (b f):
//   hit:  s_i = b f (1/z_i - 1/z_s) / sigma_disp
//             = a_i lambda_i (lambda_s - lambda_i) / (lambda_s sigma_i)
// the disparity error in units of sigma_disp (b f cancels): homoscedastic,
// unbiased for stereo noise, positive in front of the surface, negative
// behind it (inside the car or beyond). Derivatives by implicit
// differentiation of phi_z(c(lambda_s)) = 0:
//   d lambda_s = -(d phi at c, lambda fixed) / (grad phi(c) . u)
//   d s_i / d lambda_s = a_i lambda_i^2 / (lambda_s^2 sigma_i)
// and "d phi at c, lambda fixed" is the point Jacobian of point_sdf.h taken at
// the world point of c. At a grazing crossing (grad phi . u > -kMinRaySlope)
// the slope is clamped to -kMinRaySlope in the derivative (Gauss-Newton
// approximation).
//   miss: the ray passes the shape. s_i = d_i / sigma_sil,i with d_i =
// min_lambda phi_z(c(lambda)) over the grid box (the ray's clearance of the
// silhouette) and sigma_sil,i = z_i silhouette_sigma_px / f (the silhouette's
// image-space uncertainty). By the envelope theorem d d_i = d phi at
// c(lambda*), lambda* fixed.
//   E_data = w / N * sum_i rho(s_i)          (rho: the mixture, data_cost.h)
#pragma once

#include <vector>

#include "libsamp/fit/costs/data_cost.h"

namespace samp {

// Per-point classification of the disparity term (EM association, reports).
struct RayResidual {
  bool hit = false;      // the ray meets the shape
  bool grazing = false;  // ... at a grazing angle (derivative with a clamped slope)
  double value = 0.0;    // s_i before the robustifier (hit: disparity error / sigma_disp; miss: clearance / sigma_sil)
};

// Whether the disparity term can use a point: in front of the camera, its
// unit ray u from the camera centre at u . axis > 1e-3 (a positive depth).
// The fit drops the candidates that are not and counts them
// (FitSummary::num_points_behind_camera); DisparityCost refuses them.
bool InFrontOfCamera(const Eigen::Vector3d& point, const Eigen::Vector3d& camera_in_world,
                     const Eigen::Vector3d& camera_axis_in_world);

class DisparityCost : public DataCost {
 public:
  // `lookup` must outlive the cost. points and sigmas have equal, non-zero
  // size; every point in front of the camera (InFrontOfCamera); options.focal_px > 0.
  DisparityCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
                const std::vector<double>& sigmas, const DataCostOptions& options);

  bool EvaluateRows(const double* z, const double* pose, int begin, int end, double* residuals, double* jz,
                    int jz_stride, double* jp, int jp_stride) const override;

  // s_i of every point at (z, pose), before the robustifier.
  std::vector<RayResidual> RayResiduals(const double* z, const double* pose) const;

 private:
  // Residual of point i: s_i, the factor m with d s_i = m (d phi at c), c
  // (object frame) and, when g / dz_row are given, grad phi and d phi / dz at c.
  RayResidual Residual(int i, const double* phi_z, const double* o_cam, const double* u, double* m, double* c,
                       double* g, double* dz_row) const;

  std::vector<double> ray_lengths_;            // lambda_i
  std::vector<double> axis_cosines_;           // a_i = u . optical axis
  std::vector<double> inv_silhouette_sigmas_;  // 1 / sigma_sil,i
};

}  // namespace samp
