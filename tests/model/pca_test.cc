#include "libsamp/model/pca.h"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <cmath>
#include <random>

#include "libsamp/core/error.h"

namespace samp {
namespace {

Eigen::MatrixXd RandomGaussian(int rows, int cols, std::mt19937* rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd m(rows, cols);
  for (int j = 0; j < cols; ++j)
    for (int i = 0; i < rows; ++i) m(i, j) = normal(*rng);
  return m;
}

Eigen::MatrixXd Orthonormal(const Eigen::MatrixXd& m) {
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(m);
  return qr.householderQ() * Eigen::MatrixXd::Identity(m.rows(), m.cols());
}

// Samples whose centred covariance is exactly basis * diag(variances) * basis^T
// plus isotropic noise of standard deviation `noise`, around a mean of ~3 m
// (SDF-like offsets, to exercise the float centring).
struct Planted {
  Eigen::MatrixXf samples;
  Eigen::MatrixXd basis;  // D x k
  Eigen::VectorXd variances;
};

Planted Plant(int dim, int num_samples, const Eigen::VectorXd& variances, double noise,
              unsigned seed) {
  std::mt19937 rng(seed);
  const int k = int(variances.size());
  Planted planted;
  planted.variances = variances;
  planted.basis = Orthonormal(RandomGaussian(dim, k, &rng));
  // Coefficients: rows orthogonal, zero mean, squared norms (N - 1) sigma^2.
  Eigen::MatrixXd coefficients = RandomGaussian(num_samples, k, &rng);
  coefficients.rowwise() -= coefficients.colwise().mean();
  coefficients = Orthonormal(coefficients);
  const Eigen::MatrixXd a =
      (variances * double(num_samples - 1)).cwiseSqrt().asDiagonal() * coefficients.transpose();
  const Eigen::VectorXd mean = Eigen::VectorXd::Constant(dim, 3.0) + RandomGaussian(dim, 1, &rng);
  Eigen::MatrixXd x = planted.basis * a + noise * RandomGaussian(dim, num_samples, &rng);
  x.colwise() += mean;
  planted.samples = x.cast<float>();
  return planted;
}

// Cosines of the principal angles between the column spaces of a and b (orthonormal).
Eigen::VectorXd PrincipalCosines(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return Eigen::JacobiSVD<Eigen::MatrixXd>(a.transpose() * b).singularValues();
}

void ExpectRecovers(int num_samples) {
  SCOPED_TRACE("N = " + std::to_string(num_samples));
  Eigen::VectorXd variances(4);
  variances << 9.0, 4.0, 1.0, 0.25;
  const int dim = 3000;
  const Planted planted = Plant(dim, num_samples, variances, 1e-4, 7);
  PcaOptions options;
  options.num_components = 4;
  const PcaResult result = ComputePca(planted.samples, options);

  ASSERT_EQ(result.components.rows(), dim);
  ASSERT_EQ(result.components.cols(), 4);
  ASSERT_EQ(result.eigenvalues.size(), 4);
  const Eigen::MatrixXd w = result.components.cast<double>();
  EXPECT_LT((w.transpose() * w - Eigen::MatrixXd::Identity(4, 4)).cwiseAbs().maxCoeff(), 1e-5);
  const Eigen::VectorXd cosines = PrincipalCosines(planted.basis, w);
  EXPECT_GT(cosines.minCoeff(), 1.0 - 1e-5) << cosines.transpose();
  // Each component matches its planted direction (distinct variances), up to sign.
  for (int r = 0; r < 4; ++r) {
    EXPECT_GT(std::abs(planted.basis.col(r).dot(w.col(r))), 1.0 - 1e-5) << "component " << r;
  }
  for (int r = 0; r < 4; ++r) {
    EXPECT_NEAR(result.eigenvalues[r], variances[r], 1e-3 * variances[r]) << "eigenvalue " << r;
  }
  const double noise_variance = dim * 1e-8;
  EXPECT_NEAR(result.total_variance, variances.sum() + noise_variance, 1e-3);
  // The mean is the sample mean.
  const Eigen::VectorXd mean = planted.samples.cast<double>().rowwise().mean();
  EXPECT_LT((result.mean.cast<double>() - mean).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(Pca, RecoversPlantedSubspaceSpectra) { ExpectRecovers(120); }

TEST(Pca, RecoversPlantedSubspaceDenseSolver) { ExpectRecovers(12); }

TEST(Pca, FewerComponentsThanPlantedTakesTheLargest) {
  Eigen::VectorXd variances(4);
  variances << 9.0, 4.0, 1.0, 0.25;
  const Planted planted = Plant(2000, 80, variances, 1e-4, 11);
  PcaOptions options;
  options.num_components = 2;
  const PcaResult result = ComputePca(planted.samples, options);
  ASSERT_EQ(result.eigenvalues.size(), 2);
  EXPECT_NEAR(result.eigenvalues[0], 9.0, 9e-3);
  EXPECT_NEAR(result.eigenvalues[1], 4.0, 4e-3);
  const Eigen::VectorXd cosines =
      PrincipalCosines(planted.basis.leftCols(2), result.components.cast<double>());
  EXPECT_GT(cosines.minCoeff(), 1.0 - 1e-5);
  EXPECT_GT(result.num_iterations, 0);
}

TEST(Pca, MaximalNumberOfComponents) {
  // R = N - 1: every direction of the centred samples.
  std::mt19937 rng(3);
  const Eigen::MatrixXf samples = RandomGaussian(500, 6, &rng).cast<float>();
  PcaOptions options;
  options.num_components = 5;
  const PcaResult result = ComputePca(samples, options);
  EXPECT_NEAR(result.eigenvalues.sum(), result.total_variance, 1e-4 * result.total_variance);
  for (int r = 1; r < 5; ++r) EXPECT_GE(result.eigenvalues[r - 1], result.eigenvalues[r]);
}

// The float Gram kernels (libsamp/model/gram.h) against a PCA in double
// precision by SVD of the centred samples, on sizes off the kernels' tiles.
void ExpectMatchesDoubleReference(int dim, int num_samples, int num_components) {
  SCOPED_TRACE("D = " + std::to_string(dim) + ", N = " + std::to_string(num_samples));
  Eigen::VectorXd variances(8);
  variances << 9.0, 4.0, 2.0, 1.0, 0.5, 0.25, 0.125, 0.0625;
  const Planted planted = Plant(dim, num_samples, variances, 1e-2, 21);
  PcaOptions options;
  options.num_components = num_components;
  const PcaResult result = ComputePca(planted.samples, options);

  const Eigen::MatrixXd x = planted.samples.cast<double>();
  const Eigen::VectorXd mean = x.rowwise().mean();
  const Eigen::MatrixXd centred = x.colwise() - mean;
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(centred, Eigen::ComputeThinU);
  const double total = centred.squaredNorm() / (num_samples - 1);
  EXPECT_NEAR(result.total_variance, total, 1e-6 * total);
  for (int r = 0; r < num_components; ++r) {
    const double lambda = svd.singularValues()[r] * svd.singularValues()[r] / (num_samples - 1);
    EXPECT_NEAR(result.eigenvalues[r], lambda, 1e-5 * lambda) << "eigenvalue " << r;
    Eigen::VectorXd u = svd.matrixU().col(r);
    Eigen::Index arg_max = 0;
    u.cwiseAbs().maxCoeff(&arg_max);
    if (u[arg_max] < 0) u = -u;  // the same sign rule
    EXPECT_GT(u.dot(result.components.col(r).cast<double>()), 1.0 - 1e-6) << "component " << r;
  }
}

TEST(Pca, MatchesDoublePrecisionReferenceSpectra) { ExpectMatchesDoubleReference(1283, 75, 7); }

TEST(Pca, MatchesDoublePrecisionReferenceDenseSolver) {
  ExpectMatchesDoubleReference(517, 13, 5);
}

TEST(Pca, RejectsBadInput) {
  std::mt19937 rng(5);
  const Eigen::MatrixXf samples = RandomGaussian(100, 6, &rng).cast<float>();
  PcaOptions options;
  options.num_components = 6;  // > N - 1
  EXPECT_THROW(ComputePca(samples, options), Error);
  options.num_components = 0;
  EXPECT_THROW(ComputePca(samples, options), Error);
  options.num_components = 1;
  EXPECT_THROW(ComputePca(samples.leftCols(1), options), Error);
  Eigen::MatrixXf with_nan = samples;
  with_nan(17, 3) = std::nanf("");
  EXPECT_THROW(ComputePca(with_nan, options), Error);
}

TEST(Pca, RejectsRankDeficientSamples) {
  // 8 samples on a 2-dimensional affine subspace: a third component does not exist.
  Eigen::VectorXd variances(2);
  variances << 2.0, 1.0;
  const Planted planted = Plant(300, 8, variances, 0.0, 13);
  PcaOptions options;
  options.num_components = 3;
  EXPECT_THROW(ComputePca(planted.samples, options), Error);
  options.num_components = 2;
  EXPECT_NO_THROW(ComputePca(planted.samples, options));
}

}  // namespace
}  // namespace samp
