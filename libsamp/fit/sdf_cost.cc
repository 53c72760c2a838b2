#include "libsamp/fit/sdf_cost.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <mutex>

#include "libsamp/core/error.h"

namespace samp {

namespace {

// Ray distance: at most this many sphere-tracing steps, each at least half a
// voxel; Newton steps on the bracketed crossing; at most kMaxRayRatio |phi|;
// crossings with |grad phi . u| below kMinRaySlope (grazing) count as misses.
constexpr int kMaxMarchSteps = 24;
constexpr int kNewtonSteps = 3;
constexpr double kMaxRayRatio = 5.0;
constexpr double kMinRaySlope = 0.05;

}  // namespace

SdfCost::SdfCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
                 const std::vector<double>& sigmas, const SdfCostOptions& options)
    : lookup_(lookup), huber_(options.huber_threshold) {
  SAMP_CHECK(lookup != nullptr) << "SdfCost: null shape lookup";
  SAMP_CHECK(!points_in_world.empty()) << "SdfCost: no points";
  SAMP_CHECK(points_in_world.size() == sigmas.size())
      << "SdfCost: " << points_in_world.size() << " points but " << sigmas.size() << " sigmas";
  SAMP_CHECK(options.huber_threshold > 0.0) << "SdfCost: Huber threshold must be > 0";
  SAMP_CHECK(options.weight > 0.0) << "SdfCost: weight must be > 0";
  SAMP_CHECK(options.camera_in_world.allFinite()) << "SdfCost: camera centre is not finite";
  const size_t n = points_in_world.size();
  sqrt_weight_ = std::sqrt(options.weight / double(n));
  points_.resize(3 * n);
  inv_sigmas_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    SAMP_CHECK(points_in_world[i].allFinite()) << "SdfCost: point " << i << " is not finite";
    SAMP_CHECK(sigmas[i] > 0.0 && std::isfinite(sigmas[i]))
        << "SdfCost: sigma of point " << i << " must be > 0, got " << sigmas[i];
    for (int a = 0; a < 3; ++a) points_[3 * i + a] = points_in_world[i][a];
    inv_sigmas_[i] = 1.0 / sigmas[i];
  }
  if (options.ray_depth_inside) {
    rays_.resize(3 * n);
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d ray = points_in_world[i] - options.camera_in_world;
      SAMP_CHECK(ray.norm() > 0.0) << "SdfCost: point " << i << " is at the camera centre";
      for (int a = 0; a < 3; ++a) rays_[3 * i + a] = ray[a] / ray.norm();
    }
  }
  set_num_residuals(int(n));
  mutable_parameter_block_sizes()->push_back(lookup->num_components());
  mutable_parameter_block_sizes()->push_back(4);
}

bool SdfCost::Evaluate(double const* const* parameters, double* residuals,
                       double** jacobians) const {
  const int nr = lookup_->num_components();
  double* jz = jacobians ? jacobians[0] : nullptr;
  double* jp = jacobians ? jacobians[1] : nullptr;
  return EvaluateRows(parameters[0], parameters[1], 0, num_residuals(), residuals, jz, nr, jp, 4);
}

bool SdfCost::EvaluateRows(const double* z, const double* pose, int begin, int end, double* residuals,
                           double* jz, int jz_stride, double* jp, int jp_stride) const {
  const int nr = lookup_->num_components();
  const double c = std::cos(pose[3]), s = std::sin(pose[3]);
  const double* phi_z = lookup_->DenseCached(z);
  for (int row = 0; row < end - begin; ++row) {
    const int i = begin + row;
    const double dx = points_[3 * i] - pose[0];
    const double dy = points_[3 * i + 1] - pose[1];
    const double dz = points_[3 * i + 2] - pose[2];
    double o[3] = {c * dx - s * dz, dy, s * dx + c * dz};
    double g[3];
    double* dz_row = jz ? jz + size_t(row) * jz_stride : nullptr;
    double phi = lookup_->EvaluateDense(phi_z, o, jp ? g : nullptr, dz_row);
    if (!std::isfinite(phi)) return false;
    if (!rays_.empty() && phi != 0.0) {
      // Distance along the viewing ray (capped at kMaxRayRatio |phi|).
      const double* w = &rays_[3 * i];
      const double u[3] = {c * w[0] - s * w[2], w[1], s * w[0] + c * w[2]};
      double distance, crossing[3];
      double m = kMaxRayRatio;  // the cap: kMaxRayRatio phi at o
      double g_crossing[3];
      if (RayDistance(phi_z, o, phi, u, &distance, crossing, g_crossing)) {
        // phi_eff = sign(phi) distance; by implicit differentiation of
        // phi(crossing) = 0 its derivatives are those of phi at the crossing
        // times m = -1 / (grad phi . u) (RayDistance ensures grad phi . u < 0).
        m = -1.0 / (g_crossing[0] * u[0] + g_crossing[1] * u[1] + g_crossing[2] * u[2]);
        for (int a = 0; a < 3; ++a) {
          o[a] = crossing[a];
          g[a] = g_crossing[a];
        }
        if (dz_row) lookup_->EvaluateDense(phi_z, crossing, nullptr, dz_row);
        phi = phi < 0.0 ? -distance : distance;
      } else {
        phi *= m;  // g (when needed) and dz_row are phi's at o
      }
      for (int a = 0; a < 3; ++a) g[a] *= m;
      if (dz_row) {
        for (int r = 0; r < nr; ++r) dz_row[r] *= m;
      }
    }
    double d_psi = 1.0;
    const double scaled = phi * inv_sigmas_[i];  // s_i = phi / sigma_i
    residuals[row] = sqrt_weight_ * Psi(scaled, huber_, &d_psi);
    const double f = sqrt_weight_ * d_psi * inv_sigmas_[i];
    if (dz_row) {
      for (int r = 0; r < nr; ++r) dz_row[r] *= f;
    }
    if (jp) {
      double* p = jp + size_t(row) * jp_stride;
      // R grad = (c g0 + s g2, g1, -s g0 + c g2).
      p[0] = -f * (c * g[0] + s * g[2]);
      p[1] = -f * g[1];
      p[2] = -f * (-s * g[0] + c * g[2]);
      p[3] = f * (-g[0] * o[2] + g[2] * o[0]);
    }
  }
  return true;
}

bool SdfCost::RayDistance(const double* phi_z, const double* o, double phi_o, const double* u,
                          double* distance, double* c, double* g_c) const {
  const double min_step = 0.5 * lookup_->grid().voxel_size;
  const double sign = phi_o < 0.0 ? -1.0 : 1.0;  // inside: towards the camera
  auto at = [&](double d, double* p) {
    for (int a = 0; a < 3; ++a) p[a] = o[a] + sign * d * u[a];
  };
  auto same_side = [&](double v) { return sign < 0.0 ? v < 0.0 : v > 0.0; };
  // Sphere tracing: |phi| bounds the distance to the surface.
  double lo = 0.0, phi_lo = phi_o, hi = 0.0, phi_hi = phi_o;
  const double limit = kMaxRayRatio * std::abs(phi_o);
  for (int k = 0; k < kMaxMarchSteps && same_side(phi_hi) && hi <= limit; ++k) {
    lo = hi;
    phi_lo = phi_hi;
    hi = lo + std::max(std::abs(phi_lo), min_step);
    at(hi, c);
    phi_hi = lookup_->EvaluateDense(phi_z, c, nullptr, nullptr);
    if (!std::isfinite(phi_hi)) return false;
  }
  if (same_side(phi_hi)) return false;
  // Secant in the bracket [lo, hi], then Newton steps kept inside it until
  // |phi| is negligible; c and g_c are those of the final distance.
  double d = lo + (hi - lo) * phi_lo / (phi_lo - phi_hi);
  const double tolerance = 1e-9 * lookup_->grid().voxel_size;
  for (int k = 0;; ++k) {
    at(d, c);
    const double v = lookup_->EvaluateDense(phi_z, c, g_c, nullptr);
    const double slope = sign * (g_c[0] * u[0] + g_c[1] * u[1] + g_c[2] * u[2]);  // d phi / d distance
    if (k == kNewtonSteps || std::abs(v) <= tolerance || slope == 0.0 || !std::isfinite(slope)) break;
    d = std::min(std::max(d - v / slope, lo), hi);
  }
  if (d > limit) return false;
  // A crossing at a grazing angle (or none after all) counts as a miss.
  if (!(g_c[0] * u[0] + g_c[1] * u[1] + g_c[2] * u[2] < -kMinRaySlope)) return false;
  *distance = d;
  return true;
}

CompressedSdfCost::CompressedSdfCost(const ShapeLookup* lookup,
                                     const std::vector<Eigen::Vector3d>& points_in_world,
                                     const std::vector<double>& sigmas, const SdfCostOptions& options)
    : full_(lookup, points_in_world, sigmas, options),
      num_components_(lookup->num_components()) {
  set_num_residuals(num_components_ + 4 + 1);
  mutable_parameter_block_sizes()->push_back(num_components_);
  mutable_parameter_block_sizes()->push_back(4);
}

bool CompressedSdfCost::Evaluate(double const* const* parameters, double* residuals,
                                 double** jacobians) const {
  const int nr = num_components_, m = nr + 4;
  std::lock_guard<std::mutex> lock(cache_mutex_);
  const bool hit = cache_valid_ && std::equal(parameters[0], parameters[0] + nr, cache_parameters_.begin()) &&
                   std::equal(parameters[1], parameters[1] + 4, cache_parameters_.begin() + nr);
  if (!hit) {
    cache_valid_ = false;
    cache_parameters_.assign(parameters[0], parameters[0] + nr);
    cache_parameters_.insert(cache_parameters_.end(), parameters[1], parameters[1] + 4);
    cache_residuals_.resize(size_t(m) + 1);
    cache_jz_.resize(size_t(m + 1) * nr);
    cache_jp_.resize(size_t(m + 1) * 4);
    if (!Linearize(parameters[0], parameters[1])) return false;
    cache_valid_ = true;
  }
  std::copy(cache_residuals_.begin(), cache_residuals_.end(), residuals);
  if (jacobians && jacobians[0]) std::copy(cache_jz_.begin(), cache_jz_.end(), jacobians[0]);
  if (jacobians && jacobians[1]) std::copy(cache_jp_.begin(), cache_jp_.end(), jacobians[1]);
  return true;
}

bool CompressedSdfCost::Linearize(const double* z, const double* pose) const {
  using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const int n = full_.num_residuals();
  const int nr = num_components_, m = nr + 4;
  // The points in chunks whose rows stay in the L1/L2 cache: J^T J, J^T r
  // and |r|^2 are accumulated chunk by chunk (per-thread scratch).
  // J = [d/dz | d/dpose], one row per point.
  constexpr int kChunk = 256;
  thread_local std::vector<double> r_buffer, j_buffer;
  r_buffer.resize(kChunk);
  j_buffer.resize(size_t(kChunk) * m);
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(m);
  double squared_norm = 0.0;
  for (int begin = 0; begin < n; begin += kChunk) {
    const int end = std::min(n, begin + kChunk), rows = end - begin;
    if (!full_.EvaluateRows(z, pose, begin, end, r_buffer.data(), j_buffer.data(), m, j_buffer.data() + nr, m)) {
      return false;
    }
    const Eigen::Map<const Eigen::VectorXd> r(r_buffer.data(), rows);
    const Eigen::Map<const RowMatrix> j(j_buffer.data(), rows, m);
    h.selfadjointView<Eigen::Lower>().rankUpdate(j.transpose());
    g.noalias() += j.transpose() * r;
    squared_norm += r.squaredNorm();
  }
  const double eps = 1e-12 * std::max(h.trace(), 1e-300);
  h.diagonal().array() += eps;
  Eigen::LLT<Eigen::MatrixXd, Eigen::Lower> llt(h);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::VectorXd rc = llt.matrixL().solve(g);
  for (int k = 0; k < m; ++k) cache_residuals_[size_t(k)] = rc[k];
  cache_residuals_[size_t(m)] = std::sqrt(std::max(0.0, squared_norm - rc.squaredNorm()));
  // Row k of the compressed Jacobian = row k of L^T; last row zero.
  const RowMatrix lt = llt.matrixL().transpose();  // m x m, upper
  Eigen::Map<RowMatrix> jz(cache_jz_.data(), m + 1, nr), jp(cache_jp_.data(), m + 1, 4);
  jz.topRows(m) = lt.leftCols(nr);
  jz.row(m).setZero();
  jp.topRows(m) = lt.rightCols(4);
  jp.row(m).setZero();
  return true;
}

}  // namespace samp
