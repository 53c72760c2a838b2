// The shape manifold phi(z) = W z + mu on a voxel grid, its model file (one
// .vdb, docs/model_format.md); point lookups are in shape_lookup.h.
// A loaded ShapeModel is immutable and safe to share between threads: every
// const method may be called concurrently.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "libsamp/core/grid_spec.h"
#include "libsamp/sdf/vdb_io.h"

namespace samp {

struct ShapeModel {
  // 2: the file carries a checksum of its payload, verified before decoding
  // (docs/model_format.md); version 1 files are refused with that reason.
  static constexpr int kFormatVersion = 2;

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

  // Point lookups (value and gradients of phi_z, trilinear, with the outside
  // rule): ShapeLookup (libsamp/model/shape_lookup.h).

  // Throws samp::Error when sizes are inconsistent or values are not finite.
  void Check() const;

  // Writes the model file atomically.
  void Save(const std::string& path) const;
  // Loads and validates a model file; a clear samp::Error on a missing,
  // corrupt, truncated or mismatched file, a .vdb that is not a samp model, or
  // one whose grids would exceed `options` (checked before anything is decoded).
  // Peak memory is about twice options.max_dense_bytes.
  static ShapeModel Load(const std::string& path, const VdbReadOptions& options = VdbReadOptions());
};

}  // namespace samp
