// Principal component analysis of stacked grids with Spectra, never forming
// the D x D covariance: the top eigenpairs of the N x N Gram matrix of the
// centred samples give the principal directions (docs/model_format.md).
#pragma once

#include <Eigen/Core>
#include <string>

namespace samp {

struct PcaOptions {
  // Number of components to keep, 1 <= R <= N - 1.
  int num_components = 5;
  void Check() const;
};

struct PcaResult {
  Eigen::VectorXf mean;         // D
  Eigen::MatrixXf components;   // D x R, orthonormal columns, by decreasing variance
  Eigen::VectorXd eigenvalues;  // R variances sigma_i^2 (normalised by N - 1)
  double total_variance = 0.0;  // trace of the sample covariance (normalised by N - 1)
  int num_iterations = 0;       // Spectra's
};

// `samples` is D x N (one grid per column). Throws samp::Error on bad sizes or
// when Spectra does not converge (its info() is checked).
PcaResult ComputePca(const Eigen::MatrixXf& samples, const PcaOptions& options);

}  // namespace samp
