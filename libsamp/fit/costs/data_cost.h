// What the three data terms of one frame share (docs/fitting.md, "Data
// term"): ONE Ceres cost block per frame over its N points x_i (world, depth
// noise sigma_i), parameter blocks z (R values) and pose (tx, ty, tz, theta),
// residual r_i = sqrt(w / N) psi(s_i), so that
//   E_data = sum_i r_i^2 = w / N * sum_i rho(s_i),   rho = psi^2,
// with s_i the term's scaled residual (point_sdf.h, ray_depth.h,
// disparity.h). Ceres applies a LossFunction to a whole block, so the
// robustifier lives inside the block:
//   Huber (SAMP Section 3.2), threshold k:  rho(s) = s^2 (|s| <= k), 2 k |s| - k^2 (|s| > k)
//     psi(s) = s (|s| <= k), sign(s) sqrt(2 k |s| - k^2) (|s| > k)  (C^1, psi' = k / |psi| outside);
//   mixture (samp addition): the point is the surface plus Gaussian noise with
//     probability 1 - eps, or belongs to something else (background behind the
//     car, an occluder in front, a wrong match) with a flat density; the
//     negative log-likelihood, shifted to 0 at s = 0:
//     rho(s) = -2 log((exp(-s^2/2) + c) / (1 + c)),  c = exp(-s_0^2 / 2),
//     psi(s) = sign(s) sqrt(rho(s))
//   (s_0 = outlier_threshold: where the two components are equally likely;
//   rho -> rho_max = -2 log(c / (1 + c)) beyond it, so clutter and occluders
//   add a constant).
// w weights a frame against the priors (1 / T, or N_eff: FitOptions::data_weighting).
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "libsamp/model/shape_lookup.h"

namespace samp {

// Which residual a point contributes.
enum class DataTerm {
  kPaper,      // phi_z at the point / sigma_d, Huber (SAMP Section 3.2; point_sdf.h)
  kRayDepth,   // distance along the viewing ray to the surface (ray_depth.h; the fitter's default)
  kDisparity,  // disparity of the point vs that of the visible surface on its ray, mixture (disparity.h)
};
const char* DataTermName(DataTerm term);  // "paper", "ray-depth", "disparity"
// Throws samp::Error for an unknown name.
DataTerm ParseDataTerm(const std::string& name);

struct DataCostOptions {
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
  // kPaper / kRayDepth: the mixture robustifier (threshold outlier_threshold)
  // instead of Huber: a point of something else (clutter, background, a
  // neighbouring car) adds a bounded cost and no pull.
  bool mixture_loss = false;
};

// The Huber psi with threshold k and d psi / ds (null: skipped).
double HuberPsi(double s, double k, double* d_psi);
// The mixture psi with threshold s0 and d psi / ds (null: skipped).
double MixturePsi(double s, double s0, double* d_psi);
// The same with c = exp(-s0^2 / 2) given (hoisted out of a loop over points).
double MixturePsiWithC(double s, double c, double* d_psi);
// psi[k] and d_psi[k] = MixturePsiWithC(s[k], c, &d_psi[k]) for k in [0, n):
// four at a time in AVX2 lanes with glibc's vector expm1, exp and log1p
// (libmvec, at most 4 ulp each) where the CPU has AVX2 and the build found
// libmvec (MixturePsiRowsVectorised), else one at a time. The two agree to a
// few ulp, not bit for bit; each is deterministic on its own.
void MixturePsiRows(const double* s, int n, double c, double* psi, double* d_psi);
bool MixturePsiRowsVectorised();

// The camera centre in the object frame of pose (rotation (c, s) = R_y(theta)).
void CameraInObject(const Eigen::Vector3d& camera, const double* pose, double c, double s, double* o_cam);

// One point's Jacobian rows from phi's derivatives at the object-frame point o
// (R_y(theta) = (c, s)): the d/dz row (holding d phi / dz) scaled by f, and the
// pose row from the spatial gradient g: d/dt = -f R g, d/dtheta = f g . (-o_z, 0, o_x).
// Null rows are skipped.
void WriteJacobianRow(double f, double c, double s, const double* g, const double* o, int nr, double* dz_row,
                      double* pose_row);

// The data-term block of one frame: Evaluate() over all points, and
// EvaluateRows() over a range of them with strided Jacobian rows (what
// CompressedDataCost accumulates). Holds the points and 1 / sigma_i; `lookup`
// must outlive the cost. Evaluate() may be called concurrently.
class DataCost : public ceres::CostFunction {
 public:
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

  // Evaluate() for the points [begin, end) with the Jacobian rows written
  // with strides: residual of point begin + i at residuals[i], its row of
  // d/dz (R values) at jz + i jz_stride, of d/d(t, theta) (4 values) at
  // jp + i jp_stride; null jz / jp skip them. phi_z comes from the lookup's
  // per-thread dense grid of z (ShapeLookup::DenseCached).
  virtual bool EvaluateRows(const double* z, const double* pose, int begin, int end, double* residuals,
                            double* jz, int jz_stride, double* jp, int jp_stride) const = 0;

  const ShapeLookup& lookup() const { return *lookup_; }

 protected:
  // Throws samp::Error on bad input (no points, sizes differ, a sigma <= 0,
  // a non-finite point, bad options). Points at the camera centre are refused
  // when with_rays (the ray terms) and their unit rays from the camera kept.
  DataCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
           const std::vector<double>& sigmas, const DataCostOptions& options, bool with_rays);

  // Rows written at a time by WriteDistanceRows.
  static constexpr int kRowChunk = 64;

  // What the rows of one evaluation at (z, pose) share: R, the rotation
  // (c, s) = R_y(theta), phi_z's dense grid (ShapeLookup::DenseCached) and the
  // camera centre in the object frame.
  struct PoseFrame {
    int nr;
    double c, s;
    const double* phi_z;
    double o_cam[3];
  };
  PoseFrame AtPose(const double* z, const double* pose) const {
    PoseFrame f;
    f.nr = lookup_->num_components();
    f.c = std::cos(pose[3]);
    f.s = std::sin(pose[3]);
    f.phi_z = lookup_->DenseCached(z);
    CameraInObject(camera_, pose, f.c, f.s, f.o_cam);
    return f;
  }

  // Point i in the object frame of pose (rotation (c, s) = R_y(theta)):
  // o = R_y(theta)^T (x_i - t).
  void PointInObject(int i, const double* pose, double c, double s, double* o) const {
    const double dx = points_[3 * i] - pose[0];
    const double dy = points_[3 * i + 1] - pose[1];
    const double dz = points_[3 * i + 2] - pose[2];
    o[0] = c * dx - s * dz;
    o[1] = dy;
    o[2] = s * dx + c * dz;
  }

  // The unit ray of point i in the object frame: u = R_y(theta)^T w_i (with_rays).
  void RayInObject(int i, double c, double s, double* u) const {
    const double* w = &rays_[3 * i];
    u[0] = c * w[0] - s * w[2];
    u[1] = w[1];
    u[2] = s * w[0] + c * w[2];
  }

  // The rows of points [first, first + n) (n <= kRowChunk) from their signed
  // distances phi[k] (kPaper, kRayDepth): r_i = sqrt(w/N) psi(phi / sigma_i)
  // into residuals[k], the robustifier (mixture or Huber, by the options) over
  // all n at once (MixturePsiRows), then each point's Jacobian rows from
  // phi's derivatives g[k] at o[k] (WriteJacobianRow; d/dz rows at jz + k
  // jz_stride holding d phi / dz, pose rows at jp + k jp_stride; null: skipped).
  void WriteDistanceRows(int first, int n, const double* phi, const double (*g)[3], const double (*o)[3], double c,
                         double s, int nr, double* residuals, double* jz, int jz_stride, double* jp,
                         int jp_stride) const;

  // EvaluateRows of the paper's term (kPaper): phi_z and its derivatives at
  // each point's object-frame position o, then WriteDistanceRows. (RayDepthCost
  // has its own loop: phi at o first, the derivatives where the residual is taken.)
  bool DistanceRows(const double* z, const double* pose, int begin, int end, double* residuals, double* jz,
                    int jz_stride, double* jp, int jp_stride) const;

  const ShapeLookup* lookup_;
  std::vector<double> points_;      // 3 per point (world)
  std::vector<double> rays_;        // 3 per point (unit, world, from the camera), with_rays
  std::vector<double> inv_sigmas_;  // 1 / sigma_i
  Eigen::Vector3d camera_ = Eigen::Vector3d::Zero();
  double huber_ = 1.0;
  bool mixture_ = false;
  double outlier_threshold_ = 3.0;
  double mixture_c_ = 0.0;    // exp(-outlier_threshold^2 / 2), the mixture's c
  double sqrt_weight_ = 1.0;  // sqrt(w / N)
};

// The data term options.term selects (PointSdfCost, RayDepthCost, DisparityCost).
std::unique_ptr<DataCost> MakeDataCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
                                       const std::vector<double>& sigmas, const DataCostOptions& options);


}  // namespace samp
