#include "libsamp/model/pca.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Spectra/MatOp/DenseSymMatProd.h>
#include <Spectra/SymEigsSolver.h>
#include <algorithm>
#include <cmath>

#include "libsamp/core/error.h"
#include "libsamp/model/pca_option_table.h"
#include "libsamp/core/log.h"
#include "libsamp/model/gram.h"

namespace samp {
namespace {

// Rows (voxels) per block of the mean: their double sums stay in L1.
constexpr Eigen::Index kMeanBlockRows = 2048;

// Below this many samples the dense eigensolver is used: it is exact, fast at
// that size, and Spectra's Lanczos gains nothing (and needs ncv > R).
constexpr Eigen::Index kDenseSolverMaxSamples = 48;

}  // namespace

void PcaOptions::Check() const { PcaOptionTable().Check(*this); }

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
  const GramKernel kernel = BestGramKernel();
  LogDebug() << "PCA: D = " << dim << ", N = " << num_samples << ", R = " << num_components
             << ", Gram kernel " << GramKernelName(kernel);

  // Mean, accumulated in double per row over blocks of rows (the block's sums
  // stay in L1 while the columns stream past); a non-finite sum means a
  // non-finite value (a double sum of finite floats cannot overflow).
  result.mean.resize(dim);
  const float* x = samples.data();
  tbb::parallel_for(
      tbb::blocked_range<Eigen::Index>(0, (dim + kMeanBlockRows - 1) / kMeanBlockRows, 1),
      [&](const tbb::blocked_range<Eigen::Index>& range) {
        double sums[kMeanBlockRows];
        for (Eigen::Index b = range.begin(); b != range.end(); ++b) {
          const Eigen::Index row0 = b * kMeanBlockRows;
          const Eigen::Index rows = std::min(kMeanBlockRows, dim - row0);
          std::fill(sums, sums + rows, 0.0);
          for (Eigen::Index n = 0; n < num_samples; ++n) {
            const float* column = x + n * dim + row0;
            for (Eigen::Index i = 0; i < rows; ++i) sums[i] += double(column[i]);
          }
          for (Eigen::Index i = 0; i < rows; ++i) {
            SAMP_CHECK(std::isfinite(sums[i]))
                << "PCA: samples contain non-finite values (row " << row0 + i << ")";
            result.mean[row0 + i] = float(sums[i] / double(num_samples));
          }
        }
      });

  // Gram matrix of the centred samples, G = Xc^T Xc / (N - 1) (N x N), with
  // the blocked float kernel summing in double across blocks (gram.h).
  Eigen::MatrixXd gram(num_samples, num_samples);
  CentredGram(x, dim, num_samples, result.mean.data(), gram.data(), kernel);
  gram /= double(num_samples - 1);
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
  // Xc V have squared norms (N - 1) lambda. Float products summed in double
  // (gram.h), like the Gram matrix.
  const Eigen::MatrixXd projection =
      eigenvectors *
      (eigenvalues * double(num_samples - 1)).cwiseSqrt().cwiseInverse().asDiagonal();
  Eigen::MatrixXd components(dim, num_components);
  CentredProduct(x, dim, num_samples, result.mean.data(), projection.data(), num_components,
                 components.data(), kernel);
  // Remove the round-off of the float products: re-orthonormalise in order of
  // decreasing variance (signs and order kept) as W = Q R, R upper triangular
  // with positive diagonal, i.e. Gram-Schmidt, computed as a Cholesky QR:
  // R^T R = W^T W, Q = W R^-1. W is orthonormal to round-off, so W^T W is
  // within ~1e-6 of the identity and this is as accurate as modified
  // Gram-Schmidt, in two blocked passes over W instead of R^2 / 2 column sweeps.
  // R(r, r) is the norm of component r once the previous ones are removed.
  Eigen::MatrixXd wtw = Eigen::MatrixXd::Zero(num_components, num_components);
  wtw.selfadjointView<Eigen::Lower>().rankUpdate(components.transpose());
  const Eigen::LLT<Eigen::MatrixXd> cholesky(wtw);
  SAMP_CHECK(cholesky.info() == Eigen::Success)
      << "PCA: the components are linearly dependent (Cholesky of W^T W failed)";
  for (Eigen::Index r = 0; r < num_components; ++r) {
    const double norm = cholesky.matrixLLT()(r, r);
    SAMP_CHECK(norm > 0.5) << "PCA: component " << r << " degenerated (norm " << norm
                           << " before re-normalisation)";
  }
  cholesky.matrixU().solveInPlace<Eigen::OnTheRight>(components);
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
