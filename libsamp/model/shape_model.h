// The shape manifold phi(z) = W z + mu on a voxel grid, its model file (one
// .vdb, docs/model_format.md) and fast trilinear lookups with gradients.
// A loaded ShapeModel is immutable and safe to share between threads: every
// const method may be called concurrently.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "libsamp/core/grid_spec.h"

namespace samp {

struct ShapeModel {
  static constexpr int kFormatVersion = 1;

  GridSpec grid;
  Eigen::VectorXf mean;         // D = grid.NumVoxels(), x-fastest (GridSpec::Index)
  Eigen::MatrixXf components;   // D x R, orthonormal columns
  Eigen::VectorXd eigenvalues;  // R, variances sigma_i^2 (normalised by N - 1)
  // Trace of the training samples' covariance (normalised by N - 1); 0 = unknown.
  // eigenvalues.sum() / total_variance is the explained share of the variance.
  double total_variance = 0.0;
  std::vector<std::string> training_shapes;
  // The trainer's effective options as JSON text (written to the file's metadata).
  std::string options_json = "{}";

  int NumComponents() const { return int(components.cols()); }
  int64_t NumVoxels() const { return grid.NumVoxels(); }

  // Dense SDF of code z: W z + mu (D values, GridSpec::Index order). z.size() must equal R.
  Eigen::VectorXf Shape(const Eigen::VectorXd& z) const;

  // Value of phi_z at a point of the object frame (metres) by trilinear
  // interpolation of the grid samples, with optional exact gradients d/dpoint
  // (3) and d/dz (R; resized only when its size differs). Outside the grid box
  // the value is phi_z at the nearest point of the box plus the distance to the
  // box, so the value keeps growing away from the grid and the gradient (the
  // tangential part of grad phi_z at the box point plus the unit direction
  // away from the box) is never zero: -gradient points back into the grid.
  // A non-finite point gives NaN value and gradients. Throws when z.size() != R.
  double Evaluate(const Eigen::VectorXd& z, const Eigen::Vector3d& point,
                  Eigen::Vector3d* d_point = nullptr, Eigen::VectorXd* d_z = nullptr) const;

  // ---- Allocation-free lookups for hot loops (the fitter). Same maths as
  // Evaluate(); no size checks: `z` and `d_z` point to R doubles, `point` and
  // `d_point` to 3; d_point / d_z may be null. Cost ~8 (R + 1) multiply-adds.
  double Evaluate(const double* z, const double* point, double* d_point, double* d_z) const;

  // Lookup in a precomputed dense shape `shape` = Shape(z).data() (D floats),
  // 8 reads per point: the cheapest path when many points share one code and
  // d/dz is not needed (or is obtained separately with CodeGradient()).
  double EvaluateDense(const float* shape, const double* point, double* d_point) const;

  // d phi_z(point) / dz (R values into d_z); independent of z because phi is
  // linear in z: the trilinear weights applied to the rows of W (at the
  // nearest box point when outside the grid).
  void CodeGradient(const double* point, double* d_z) const;

  // Throws samp::Error when sizes are inconsistent or values are not finite.
  void Check() const;

  // Writes the model file atomically.
  void Save(const std::string& path) const;
  // Loads and validates a model file; a clear samp::Error on a missing,
  // corrupt, truncated or mismatched file, or a .vdb that is not a samp model.
  static ShapeModel Load(const std::string& path);
};

}  // namespace samp
