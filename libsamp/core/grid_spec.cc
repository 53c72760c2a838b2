#include "libsamp/core/grid_spec.h"

#include <cmath>
#include <sstream>

#include "libsamp/core/error.h"

namespace samp {

GridSpec GridSpec::Car(double length, double height, double width, double voxel_size) {
  SAMP_CHECK(std::isfinite(length) && std::isfinite(height) && std::isfinite(width) && length > 0.0 &&
             height > 0.0 && width > 0.0)
      << "car grid: length, height and width must be positive, got " << length << " x " << height << " x "
      << width << " m";
  const double bottom = 0.5;  // the grid's bottom face below the car's bottom centre (y down), m
  return FromBox(Eigen::Vector3d(-length / 2.0, bottom - height, -width / 2.0),
                 Eigen::Vector3d(length / 2.0, bottom, width / 2.0), voxel_size);
}

GridSpec GridSpec::CarDefault(double voxel_size) { return Car(6.0, 2.8, 2.8, voxel_size); }

Eigen::Vector3d GridSpec::Size() const {
  const Eigen::Vector3d size = MaxCorner() - MinCorner();
  return (size * 1e6).array().round() / 1e6;
}

GridSpec GridSpec::FromBox(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner,
                           double voxel_size) {
  SAMP_CHECK(voxel_size > 0.0) << "grid voxel_size must be > 0, got " << voxel_size;
  SAMP_CHECK((max_corner.array() > min_corner.array()).all())
      << "grid box max corner must exceed min corner";
  GridSpec spec;
  spec.voxel_size = voxel_size;
  spec.origin = min_corner;
  for (int a = 0; a < 3; ++a) {
    spec.dims[a] = int(std::ceil((max_corner[a] - min_corner[a]) / voxel_size - 1e-9)) + 1;
  }
  spec.Check();
  return spec;
}

bool GridSpec::operator==(const GridSpec& other) const {
  return dims == other.dims && std::abs(voxel_size - other.voxel_size) < 1e-9 &&
         (origin - other.origin).cwiseAbs().maxCoeff() < 1e-7;
}

void GridSpec::Check() const {
  SAMP_CHECK(std::isfinite(voxel_size) && voxel_size > 0.0)
      << "grid voxel_size must be a positive number, got " << voxel_size;
  SAMP_CHECK(origin.allFinite()) << "grid origin must be finite";
  SAMP_CHECK((dims.array() >= 2).all()) << "grid dims must be >= 2 along each axis, got "
                                         << dims.transpose();
  SAMP_CHECK(NumVoxels() <= int64_t(1) << 31) << "grid has too many voxels: " << NumVoxels();
}

std::string GridSpec::ToString() const {
  std::ostringstream s;
  const Eigen::Vector3d max_corner = MaxCorner();
  s << dims.x() << "x" << dims.y() << "x" << dims.z() << " voxels of " << voxel_size
    << " m, x [" << origin.x() << ", " << max_corner.x() << "], y [" << origin.y() << ", "
    << max_corner.y() << "], z [" << origin.z() << ", " << max_corner.z() << "]";
  return s.str();
}

}  // namespace samp
