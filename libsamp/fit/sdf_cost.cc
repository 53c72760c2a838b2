#include "libsamp/fit/sdf_cost.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "libsamp/core/error.h"

namespace samp {

SdfCost::SdfCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
                 const std::vector<double>& sigmas, double huber_threshold, double weight)
    : lookup_(lookup), huber_(huber_threshold) {
  SAMP_CHECK(lookup != nullptr) << "SdfCost: null shape lookup";
  SAMP_CHECK(!points_in_world.empty()) << "SdfCost: no points";
  SAMP_CHECK(points_in_world.size() == sigmas.size())
      << "SdfCost: " << points_in_world.size() << " points but " << sigmas.size() << " sigmas";
  SAMP_CHECK(huber_threshold > 0.0) << "SdfCost: Huber threshold must be > 0";
  SAMP_CHECK(weight > 0.0) << "SdfCost: weight must be > 0";
  const size_t n = points_in_world.size();
  sqrt_weight_ = std::sqrt(weight / double(n));
  points_.resize(3 * n);
  inv_sigmas_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    SAMP_CHECK(points_in_world[i].allFinite()) << "SdfCost: point " << i << " is not finite";
    SAMP_CHECK(sigmas[i] > 0.0 && std::isfinite(sigmas[i]))
        << "SdfCost: sigma of point " << i << " must be > 0, got " << sigmas[i];
    for (int a = 0; a < 3; ++a) points_[3 * i + a] = points_in_world[i][a];
    inv_sigmas_[i] = 1.0 / sigmas[i];
  }
  set_num_residuals(int(n));
  mutable_parameter_block_sizes()->push_back(lookup->num_components());
  mutable_parameter_block_sizes()->push_back(4);
}

double SdfCost::Psi(double s, double k, double* d_psi) {
  const double a = std::abs(s);
  if (a <= k) {
    if (d_psi) *d_psi = 1.0;
    return s;
  }
  const double root = std::sqrt(2.0 * k * a - k * k);
  if (d_psi) *d_psi = k / root;
  return s > 0.0 ? root : -root;
}

bool SdfCost::Evaluate(double const* const* parameters, double* residuals,
                       double** jacobians) const {
  const double* z = parameters[0];
  const double* pose = parameters[1];
  const int nr = lookup_->num_components();
  const int n = num_residuals();
  const double c = std::cos(pose[3]), s = std::sin(pose[3]);
  double* jz = jacobians ? jacobians[0] : nullptr;
  double* jp = jacobians ? jacobians[1] : nullptr;
  const bool need_point_gradient = jp != nullptr;
  for (int i = 0; i < n; ++i) {
    const double dx = points_[3 * i] - pose[0];
    const double dy = points_[3 * i + 1] - pose[1];
    const double dz = points_[3 * i + 2] - pose[2];
    const double o[3] = {c * dx - s * dz, dy, s * dx + c * dz};
    double g[3];
    double* dz_row = jz ? jz + size_t(i) * nr : nullptr;
    const double phi = lookup_->Evaluate(z, o, need_point_gradient ? g : nullptr, dz_row);
    if (!std::isfinite(phi)) return false;
    double d_psi = 1.0;
    const double scaled = phi * inv_sigmas_[i];  // s_i = phi / sigma_i
    residuals[i] = sqrt_weight_ * Psi(scaled, huber_, &d_psi);
    const double f = sqrt_weight_ * d_psi * inv_sigmas_[i];
    if (dz_row) {
      for (int r = 0; r < nr; ++r) dz_row[r] *= f;
    }
    if (jp) {
      double* row = jp + size_t(i) * 4;
      // R grad = (c g0 + s g2, g1, -s g0 + c g2).
      row[0] = -f * (c * g[0] + s * g[2]);
      row[1] = -f * g[1];
      row[2] = -f * (-s * g[0] + c * g[2]);
      row[3] = f * (-g[0] * o[2] + g[2] * o[0]);
    }
  }
  return true;
}

CompressedSdfCost::CompressedSdfCost(const ShapeLookup* lookup,
                                     const std::vector<Eigen::Vector3d>& points_in_world,
                                     const std::vector<double>& sigmas, double huber_threshold,
                                     double weight)
    : full_(lookup, points_in_world, sigmas, huber_threshold, weight),
      num_components_(lookup->num_components()) {
  set_num_residuals(num_components_ + 4 + 1);
  mutable_parameter_block_sizes()->push_back(num_components_);
  mutable_parameter_block_sizes()->push_back(4);
}

bool CompressedSdfCost::Evaluate(double const* const* parameters, double* residuals,
                                 double** jacobians) const {
  using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const int n = full_.num_residuals();
  const int nr = num_components_, m = nr + 4;
  // Per-thread scratch (N x R, N x 4, N): avoids large allocations per call.
  thread_local std::vector<double> r_buffer, jz_buffer, jp_buffer;
  r_buffer.resize(size_t(n));
  const bool need_jacobians = jacobians && (jacobians[0] || jacobians[1]);
  if (!need_jacobians) {
    if (!full_.Evaluate(parameters, r_buffer.data(), nullptr)) return false;
    const Eigen::Map<const Eigen::VectorXd> r(r_buffer.data(), n);
    for (int k = 0; k < m; ++k) residuals[k] = 0.0;
    residuals[m] = r.norm();
    return true;
  }
  jz_buffer.resize(size_t(n) * nr);
  jp_buffer.resize(size_t(n) * 4);
  double* full_jacobians[2] = {jz_buffer.data(), jp_buffer.data()};
  if (!full_.Evaluate(parameters, r_buffer.data(), full_jacobians)) return false;
  const Eigen::Map<const Eigen::VectorXd> r(r_buffer.data(), n);
  const Eigen::Map<const RowMatrix> jz(jz_buffer.data(), n, nr);
  const Eigen::Map<const RowMatrix> jp(jp_buffer.data(), n, 4);
  Eigen::MatrixXd h(m, m);
  h.topLeftCorner(nr, nr).noalias() = jz.transpose() * jz;
  h.topRightCorner(nr, 4).noalias() = jz.transpose() * jp;
  h.bottomRightCorner(4, 4).noalias() = jp.transpose() * jp;
  h.bottomLeftCorner(4, nr) = h.topRightCorner(nr, 4).transpose();
  Eigen::VectorXd g(m);
  g.head(nr).noalias() = jz.transpose() * r;
  g.tail(4).noalias() = jp.transpose() * r;
  const double eps = 1e-12 * std::max(h.trace(), 1e-300);
  h.diagonal().array() += eps;
  Eigen::LLT<Eigen::MatrixXd> llt(h);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::VectorXd rc = llt.matrixL().solve(g);
  for (int k = 0; k < m; ++k) residuals[k] = rc[k];
  residuals[m] = std::sqrt(std::max(0.0, r.squaredNorm() - rc.squaredNorm()));
  const RowMatrix lt = llt.matrixL().transpose();  // m x m, upper
  // Row k of the compressed Jacobian = row k of L^T; last row zero.
  if (jacobians[0]) {
    Eigen::Map<RowMatrix> out(jacobians[0], m + 1, nr);
    out.topRows(m) = lt.leftCols(nr);
    out.row(m).setZero();
  }
  if (jacobians[1]) {
    Eigen::Map<RowMatrix> out(jacobians[1], m + 1, 4);
    out.topRows(m) = lt.rightCols(4);
    out.row(m).setZero();
  }
  return true;
}

}  // namespace samp
