// Fast trilinear lookups of phi_z = W z + mu for the fitter's cost functions.
// The model's mean and components are re-laid out once, voxel-major
// ([mu, W_1 .. W_R] contiguous per voxel, doubles), so that one lookup reads
// 8 contiguous rows of R + 1 numbers: value, gradient in the point and
// gradient in the code in ~8 (R + 1) + 30 multiply-adds, no allocation.
// Same maths as ShapeModel::Evaluate, including the outside rule: outside the
// grid box the value is phi_z at the nearest box point plus the distance to the
// box, so the gradient never vanishes and -gradient points back into the grid.
// Immutable after construction; const methods are safe to call concurrently.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "libsamp/core/grid_spec.h"
#include "libsamp/core/mesh.h"
#include "libsamp/model/shape_model.h"

namespace samp {

class ShapeLookup {
 public:
  // Copies (re-lays out) the model; throws samp::Error on inconsistent sizes.
  explicit ShapeLookup(const ShapeModel& model);

  int num_components() const { return num_components_; }
  const GridSpec& grid() const { return grid_; }
  // sigma_i = sqrt(eigenvalue_i), R values.
  const Eigen::VectorXd& sigmas() const { return sigmas_; }

  // phi_z(point) with optional d/dpoint (3) and d/dz (R). `z` holds R numbers,
  // `point` 3 (object frame, metres). Null gradient pointers are skipped.
  double Evaluate(const double* z, const double* point, double* d_point, double* d_z) const;
  double Evaluate(const Eigen::VectorXd& z, const Eigen::Vector3d& point,
                  Eigen::Vector3d* d_point = nullptr, Eigen::VectorXd* d_z = nullptr) const;

  // Dense phi_z on the grid (D floats, GridSpec::Index order).
  std::vector<float> Dense(const Eigen::VectorXd& z) const;

  // Bounding box of the voxels with phi_z < 0, refined by linear interpolation
  // of the zero crossing along each axis (object frame). Empty box when phi_z
  // is nowhere negative.
  AlignedBox InsideBox(const Eigen::VectorXd& z) const;

 private:
  GridSpec grid_;
  int num_components_ = 0;
  int stride_ = 1;                   // R + 1
  std::vector<double> table_;        // D x (R + 1), voxel-major
  Eigen::VectorXd sigmas_;
  Eigen::Vector3d max_corner_;
  double inv_voxel_ = 1.0;
};

}  // namespace samp
