// The shape manifold phi(z) = W z + mu on a voxel grid, its model file (one
// .vdb, docs/model_format.md) and fast trilinear lookups with gradients.
// A loaded ShapeModel is immutable and safe to share between threads.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "libsamp/core/grid_spec.h"

namespace samp {

struct ShapeModel {
  static constexpr int kFormatVersion = 1;

  GridSpec grid;
  Eigen::VectorXf mean;         // D = grid.NumVoxels()
  Eigen::MatrixXf components;   // D x R
  Eigen::VectorXd eigenvalues;  // R, variances sigma_i^2
  std::vector<std::string> training_shapes;
  // The trainer's effective options as JSON text (written to the file's metadata).
  std::string options_json = "{}";

  int NumComponents() const { return int(components.cols()); }
  int64_t NumVoxels() const { return grid.NumVoxels(); }

  // Dense SDF of code z: W z + mu. z.size() must equal R.
  Eigen::VectorXf Shape(const Eigen::VectorXd& z) const;

  // Value of phi_z at a point of the object frame by trilinear interpolation,
  // with optional gradients d/dpoint (3) and d/dz (R). Outside the grid the value
  // is the boundary value at the nearest grid point plus the distance to the
  // grid box, so the gradient still points back into the grid.
  double Evaluate(const Eigen::VectorXd& z, const Eigen::Vector3d& point,
                  Eigen::Vector3d* d_point = nullptr, Eigen::VectorXd* d_z = nullptr) const;

  // Throws samp::Error when sizes are inconsistent.
  void Check() const;

  // Writes the model file atomically.
  void Save(const std::string& path) const;
  // Loads and validates a model file; a clear samp::Error on a missing,
  // corrupt, truncated or mismatched file, or a .vdb that is not a samp model.
  static ShapeModel Load(const std::string& path);
};

}  // namespace samp
