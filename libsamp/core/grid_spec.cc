#include "libsamp/core/grid_spec.h"

#include <cmath>
#include <sstream>

#include "libsamp/core/error.h"

namespace samp {

GridSpec GridSpec::CarDefault(double voxel_size) {
  return FromBox(Eigen::Vector3d(-3.0, -2.3, -1.4), Eigen::Vector3d(3.0, 0.5, 1.4), voxel_size);
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
