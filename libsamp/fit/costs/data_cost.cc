#include "libsamp/fit/costs/data_cost.h"

#include <cmath>

#include "libsamp/core/error.h"
#include "libsamp/fit/costs/disparity.h"
#include "libsamp/fit/costs/point_sdf.h"
#include "libsamp/fit/costs/ray_depth.h"

namespace samp {

void CameraInObject(const Eigen::Vector3d& camera, const double* pose, double c, double s, double* o_cam) {
  const double dx = camera[0] - pose[0], dy = camera[1] - pose[1], dz = camera[2] - pose[2];
  o_cam[0] = c * dx - s * dz;
  o_cam[1] = dy;
  o_cam[2] = s * dx + c * dz;
}

const char* DataTermName(DataTerm term) {
  switch (term) {
    case DataTerm::kPaper: return "paper";
    case DataTerm::kRayDepth: return "ray-depth";
    case DataTerm::kDisparity: return "disparity";
  }
  return "?";
}

DataTerm ParseDataTerm(const std::string& name) {
  for (DataTerm t : {DataTerm::kPaper, DataTerm::kRayDepth, DataTerm::kDisparity}) {
    if (name == DataTermName(t)) return t;
  }
  SAMP_THROW() << "unknown data term '" << name << "' (paper, ray-depth, disparity)";
}

double HuberPsi(double s, double k, double* d_psi) {
  const double a = std::abs(s);
  if (a <= k) {
    if (d_psi) *d_psi = 1.0;
    return s;
  }
  const double root = std::sqrt(2.0 * k * a - k * k);
  if (d_psi) *d_psi = k / root;
  return s > 0.0 ? root : -root;
}

double MixturePsi(double s, double s0, double* d_psi) { return MixturePsiWithC(s, std::exp(-0.5 * s0 * s0), d_psi); }

double MixturePsiWithC(double s, double c, double* d_psi) {
  const double e = std::exp(-0.5 * s * s);
  if (s == 0.0) {
    if (d_psi) *d_psi = 1.0 / std::sqrt(1.0 + c);
    return 0.0;
  }
  // rho = -2 log((e + c) / (1 + c)) = 2 log1p((1 - e) / (e + c)), stable for small s.
  const double rho = 2.0 * std::log1p(-std::expm1(-0.5 * s * s) / (e + c));
  const double root = std::sqrt(rho);
  if (d_psi) *d_psi = root > 0.0 ? std::abs(s) * e / ((e + c) * root) : 1.0 / std::sqrt(1.0 + c);
  return s > 0.0 ? root : -root;
}

void WriteJacobianRow(double f, double c, double s, const double* g, const double* o, int nr, double* dz_row,
                      double* pose_row) {
  if (dz_row) {
    for (int r = 0; r < nr; ++r) dz_row[r] *= f;
  }
  if (pose_row) {
    pose_row[0] = -f * (c * g[0] + s * g[2]);
    pose_row[1] = -f * g[1];
    pose_row[2] = -f * (-s * g[0] + c * g[2]);
    pose_row[3] = f * (-g[0] * o[2] + g[2] * o[0]);
  }
}

DataCost::DataCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
                   const std::vector<double>& sigmas, const DataCostOptions& options, bool with_rays)
    : lookup_(lookup), huber_(options.huber_threshold), mixture_(options.mixture_loss) {
  SAMP_CHECK(lookup != nullptr) << "DataCost: null shape lookup";
  SAMP_CHECK(!points_in_world.empty()) << "DataCost: no points";
  SAMP_CHECK(points_in_world.size() == sigmas.size())
      << "DataCost: " << points_in_world.size() << " points but " << sigmas.size() << " sigmas";
  SAMP_CHECK(options.huber_threshold > 0.0) << "DataCost: Huber threshold must be > 0";
  SAMP_CHECK(options.weight > 0.0) << "DataCost: weight must be > 0";
  SAMP_CHECK(options.camera_in_world.allFinite()) << "DataCost: camera centre is not finite";
  const size_t n = points_in_world.size();
  sqrt_weight_ = std::sqrt(options.weight / double(n));
  points_.resize(3 * n);
  inv_sigmas_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    SAMP_CHECK(points_in_world[i].allFinite()) << "DataCost: point " << i << " is not finite";
    SAMP_CHECK(sigmas[i] > 0.0 && std::isfinite(sigmas[i]))
        << "DataCost: sigma of point " << i << " must be > 0, got " << sigmas[i];
    for (int a = 0; a < 3; ++a) points_[3 * i + a] = points_in_world[i][a];
    inv_sigmas_[i] = 1.0 / sigmas[i];
  }
  camera_ = options.camera_in_world;
  outlier_threshold_ = options.outlier_threshold;
  SAMP_CHECK(!mixture_ || outlier_threshold_ > 0.0) << "DataCost: outlier_threshold must be > 0";
  mixture_c_ = std::exp(-0.5 * outlier_threshold_ * outlier_threshold_);
  if (with_rays) {
    rays_.resize(3 * n);
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d ray = points_in_world[i] - options.camera_in_world;
      SAMP_CHECK(ray.norm() > 0.0) << "DataCost: point " << i << " is at the camera centre";
      for (int a = 0; a < 3; ++a) rays_[3 * i + a] = ray[a] / ray.norm();
    }
  }
  set_num_residuals(int(n));
  mutable_parameter_block_sizes()->push_back(lookup->num_components());
  mutable_parameter_block_sizes()->push_back(4);
}

bool DataCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const int nr = lookup_->num_components();
  double* jz = jacobians ? jacobians[0] : nullptr;
  double* jp = jacobians ? jacobians[1] : nullptr;
  return EvaluateRows(parameters[0], parameters[1], 0, num_residuals(), residuals, jz, nr, jp, 4);
}

std::unique_ptr<DataCost> MakeDataCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
                                       const std::vector<double>& sigmas, const DataCostOptions& options) {
  switch (options.term) {
    case DataTerm::kPaper: return std::make_unique<PointSdfCost>(lookup, points_in_world, sigmas, options);
    case DataTerm::kRayDepth: return std::make_unique<RayDepthCost>(lookup, points_in_world, sigmas, options);
    case DataTerm::kDisparity: return std::make_unique<DisparityCost>(lookup, points_in_world, sigmas, options);
  }
  SAMP_THROW() << "MakeDataCost: unknown data term";
}

}  // namespace samp
