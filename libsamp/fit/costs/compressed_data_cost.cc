#include "libsamp/fit/costs/compressed_data_cost.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "libsamp/core/error.h"

namespace samp {

CompressedDataCost::CompressedDataCost(std::unique_ptr<DataCost> full)
    : full_(std::move(full)), num_components_(full_->lookup().num_components()) {
  set_num_residuals(num_components_ + 4 + 1);
  mutable_parameter_block_sizes()->push_back(num_components_);
  mutable_parameter_block_sizes()->push_back(4);
}

bool CompressedDataCost::Evaluate(double const* const* parameters, double* residuals,
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

bool CompressedDataCost::Linearize(const double* z, const double* pose) const {
  using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const int n = full_->num_residuals();
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
    if (!full_->EvaluateRows(z, pose, begin, end, r_buffer.data(), j_buffer.data(), m, j_buffer.data() + nr, m)) {
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
