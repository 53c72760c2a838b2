#include "libsamp/model/pca.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <Spectra/MatOp/DenseSymMatProd.h>
#include <Spectra/SymEigsSolver.h>
#include <algorithm>
#include <cmath>

#include "libsamp/core/error.h"
#include "libsamp/core/log.h"

namespace samp {
namespace {

// Rows (voxels) are processed in blocks of this many: a block of centred
// samples (kBlockRows x N floats) stays in cache-friendly GEMM panels and the
// D x N centred matrix is never materialised.
constexpr Eigen::Index kBlockRows = 2048;

// Below this many samples the dense eigensolver is used: it is exact, fast at
// that size, and Spectra's Lanczos gains nothing (and needs ncv > R).
constexpr Eigen::Index kDenseSolverMaxSamples = 48;

}  // namespace

void PcaOptions::Check() const {
  SAMP_CHECK(num_components >= 1) << "PcaOptions::num_components must be >= 1, got "
                                  << num_components;
}

PcaResult ComputePca(const Eigen::MatrixXf& samples, const PcaOptions& options) {
  options.Check();
  const Eigen::Index dim = samples.rows();
  const Eigen::Index num_samples = samples.cols();
  const Eigen::Index num_components = options.num_components;
  SAMP_CHECK(dim >= 1) << "PCA: samples have no rows";
  SAMP_CHECK(num_samples >= 2) << "PCA needs at least 2 samples, got " << num_samples;
  SAMP_CHECK(num_components <= num_samples - 1)
      << "PCA: num_components (" << num_components << ") must be <= number of samples - 1 ("
      << num_samples - 1 << ")";
  SAMP_CHECK(num_components <= dim) << "PCA: num_components (" << num_components
                                    << ") exceeds the dimension " << dim;

  PcaResult result;
  const Eigen::Index num_blocks = (dim + kBlockRows - 1) / kBlockRows;
  const tbb::blocked_range<Eigen::Index> blocks(0, num_blocks, 1);

  // Mean, accumulated in double per row; also checks that every value is finite.
  result.mean.resize(dim);
  tbb::parallel_for(blocks, [&](const tbb::blocked_range<Eigen::Index>& range) {
    for (Eigen::Index b = range.begin(); b != range.end(); ++b) {
      const Eigen::Index row0 = b * kBlockRows;
      const Eigen::Index rows = std::min(kBlockRows, dim - row0);
      const auto block = samples.middleRows(row0, rows);
      SAMP_CHECK(block.allFinite()) << "PCA: samples contain non-finite values (rows " << row0
                                    << ".." << row0 + rows - 1 << ")";
      result.mean.segment(row0, rows) =
          (block.cast<double>().rowwise().sum() / double(num_samples)).cast<float>();
    }
  });

  // Gram matrix of the centred samples, G = Xc^T Xc / (N - 1) (N x N): each
  // thread accumulates the lower triangle over its row blocks with a float
  // rank update (GEMM), summed in double.
  tbb::combinable<Eigen::MatrixXd> gram_parts(
      [&] { return Eigen::MatrixXd::Zero(num_samples, num_samples).eval(); });
  tbb::parallel_for(blocks, [&](const tbb::blocked_range<Eigen::Index>& range) {
    Eigen::MatrixXf centred;
    Eigen::MatrixXf block_gram(num_samples, num_samples);
    Eigen::MatrixXd& gram = gram_parts.local();
    for (Eigen::Index b = range.begin(); b != range.end(); ++b) {
      const Eigen::Index row0 = b * kBlockRows;
      const Eigen::Index rows = std::min(kBlockRows, dim - row0);
      centred = samples.middleRows(row0, rows).colwise() - result.mean.segment(row0, rows);
      block_gram.setZero();
      block_gram.selfadjointView<Eigen::Lower>().rankUpdate(centred.transpose());
      gram.triangularView<Eigen::Lower>() += block_gram.cast<double>();
    }
  });
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(num_samples, num_samples);
  gram_parts.combine_each([&](const Eigen::MatrixXd& part) { gram += part; });
  gram /= double(num_samples - 1);
  gram = gram.selfadjointView<Eigen::Lower>();  // full symmetric matrix
  result.total_variance = gram.trace();

  // Top R eigenpairs of G.
  Eigen::VectorXd eigenvalues;
  Eigen::MatrixXd eigenvectors;  // N x R
  if (num_samples <= kDenseSolverMaxSamples) {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(gram);
    SAMP_CHECK(solver.info() == Eigen::Success)
        << "PCA: the dense eigensolver failed on the " << num_samples << "x" << num_samples
        << " Gram matrix";
    // Ascending order: take the last R, reversed.
    eigenvalues = solver.eigenvalues().tail(num_components).reverse();
    eigenvectors = solver.eigenvectors().rightCols(num_components).rowwise().reverse();
    result.num_iterations = 0;
  } else {
    Spectra::DenseSymMatProd<double> op(gram);
    const Eigen::Index ncv =
        std::min<Eigen::Index>(num_samples, std::max<Eigen::Index>(2 * num_components + 1, 20));
    Spectra::SymEigsSolver<Spectra::DenseSymMatProd<double>> eigs(op, num_components, ncv);
    eigs.init();
    eigs.compute(Spectra::SortRule::LargestAlge, 1000, 1e-10);
    SAMP_CHECK(eigs.info() == Spectra::CompInfo::Successful)
        << "PCA: Spectra did not converge on the " << num_samples << "x" << num_samples
        << " Gram matrix (info " << int(eigs.info()) << ", " << eigs.num_iterations()
        << " iterations, R = " << num_components << ")";
    eigenvalues = eigs.eigenvalues();
    eigenvectors = eigs.eigenvectors();
    result.num_iterations = int(eigs.num_iterations());
  }
  SAMP_CHECK(eigenvalues.size() == num_components && eigenvectors.cols() == num_components)
      << "PCA: the eigensolver returned " << eigenvalues.size() << " eigenpairs, wanted "
      << num_components;

  // A direction with (numerically) zero variance has no defined component; the
  // float Gram matrix resolves eigenvalues to ~1e-7 of the total variance.
  const double tiny = 1e-7 * std::max(result.total_variance, 1e-300);
  for (Eigen::Index r = 0; r < num_components; ++r) {
    SAMP_CHECK(std::isfinite(eigenvalues[r]) && eigenvalues[r] > tiny)
        << "PCA: the samples span only " << r << " independent directions, fewer than the "
        << num_components << " components asked for (eigenvalue " << r << " = "
        << eigenvalues[r] << ")";
  }
  result.eigenvalues = eigenvalues;

  // Principal directions W = Xc V diag(1 / sqrt((N - 1) lambda)): the columns of
  // Xc V have squared norms (N - 1) lambda. Computed per row block in double.
  const Eigen::MatrixXd projection =
      eigenvectors *
      (eigenvalues * double(num_samples - 1)).cwiseSqrt().cwiseInverse().asDiagonal();
  Eigen::MatrixXd components(dim, num_components);
  tbb::parallel_for(blocks, [&](const tbb::blocked_range<Eigen::Index>& range) {
    for (Eigen::Index b = range.begin(); b != range.end(); ++b) {
      const Eigen::Index row0 = b * kBlockRows;
      const Eigen::Index rows = std::min(kBlockRows, dim - row0);
      const Eigen::MatrixXd centred =
          (samples.middleRows(row0, rows).colwise() - result.mean.segment(row0, rows))
              .cast<double>();
      components.middleRows(row0, rows).noalias() = centred * projection;
    }
  });
  // Remove the round-off of the float Gram matrix: re-orthonormalise (modified
  // Gram-Schmidt, in order of decreasing variance, so signs and order are kept).
  for (Eigen::Index r = 0; r < num_components; ++r) {
    for (Eigen::Index q = 0; q < r; ++q) {
      components.col(r) -= components.col(q).dot(components.col(r)) * components.col(q);
    }
    const double norm = components.col(r).norm();
    SAMP_CHECK(norm > 0.5) << "PCA: component " << r << " degenerated (norm " << norm
                           << " before re-normalisation)";
    components.col(r) /= norm;
  }
  // Deterministic sign: the largest-magnitude entry of each component is positive.
  for (Eigen::Index r = 0; r < num_components; ++r) {
    Eigen::Index arg_max = 0;
    components.col(r).cwiseAbs().maxCoeff(&arg_max);
    if (components(arg_max, r) < 0) components.col(r) *= -1.0;
  }
  result.components = components.cast<float>();
  return result;
}

}  // namespace samp
