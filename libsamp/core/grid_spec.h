// A regular, axis-aligned metric voxel grid in the canonical object frame.
// Sample (i, j, k) sits at world position origin + voxel_size * (i, j, k);
// values are stored x-fastest: index = i + dims.x * (j + dims.y * k).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>

namespace samp {

struct GridSpec {
  // World position of sample (0, 0, 0) in metres (object frame).
  Eigen::Vector3d origin = Eigen::Vector3d(-3.0, -2.3, -1.4);
  // Edge length of a voxel in metres.
  double voxel_size = 0.1;
  // Number of samples along x, y, z.
  Eigen::Vector3i dims = Eigen::Vector3i(61, 29, 29);

  // A car grid: a length x height x width box (m) around a car whose
  // bottom-centre is the origin: x in [-length/2, length/2], y in
  // [0.5 - height, 0.5] (down: its bottom face 0.5 m below the car's bottom),
  // z in [-width/2, width/2], sampled at `voxel_size` (rounded outwards to
  // whole voxels, FromBox).
  static GridSpec Car(double length, double height, double width, double voxel_size = 0.1);
  // The default car grid, Car(6.0, 2.8, 2.8): x in [-3.0, 3.0], y in
  // [-2.3, 0.5], z in [-1.4, 1.4].
  static GridSpec CarDefault(double voxel_size = 0.1);
  // The box's edge lengths (x, y, z) = MaxCorner() - MinCorner(), to the
  // micrometre (so that Car(Size(), v) of a Car grid gives its box back).
  Eigen::Vector3d Size() const;
  // A grid covering [min_corner, max_corner] at `voxel_size` (rounded outwards).
  static GridSpec FromBox(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner,
                          double voxel_size);

  int64_t NumVoxels() const { return int64_t(dims.x()) * dims.y() * dims.z(); }
  int64_t Index(int i, int j, int k) const {
    return i + int64_t(dims.x()) * (j + int64_t(dims.y()) * k);
  }
  Eigen::Vector3d Position(int i, int j, int k) const {
    return origin + voxel_size * Eigen::Vector3d(i, j, k);
  }
  Eigen::Vector3d MinCorner() const { return origin; }
  Eigen::Vector3d MaxCorner() const { return origin + voxel_size * (dims.cast<double>().array() - 1.0).matrix(); }
  // Continuous voxel coordinates of a world point (sample (i,j,k) at integers).
  Eigen::Vector3d ToVoxel(const Eigen::Vector3d& point) const { return (point - origin) / voxel_size; }

  bool operator==(const GridSpec& other) const;
  bool operator!=(const GridSpec& other) const { return !(*this == other); }

  // Throws samp::Error naming the field when the spec is invalid.
  void Check() const;
  std::string ToString() const;
};

}  // namespace samp
