#include "libsamp/sdf/surface.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <algorithm>
#include <cmath>

#include "libsamp/core/error.h"

namespace samp {
namespace {

Mesh ExtractSurfaceImpl(const GridSpec& grid, const float* values, int64_t size, double isovalue) {
  grid.Check();
  SAMP_CHECK(size == grid.NumVoxels())
      << "ExtractSurface: " << size << " values for a grid of " << grid.NumVoxels()
      << " voxels (" << grid.ToString() << ")";
  SAMP_CHECK(std::isfinite(isovalue)) << "ExtractSurface: isovalue must be finite";
  openvdb::initialize();  // idempotent and thread-safe

  // Every sample becomes an active voxel; the background (the field outside the
  // grid) lies above the isovalue, so shapes cut by the border are closed.
  float max_value = -std::numeric_limits<float>::infinity();
  bool below = false;
  for (int64_t i = 0; i < size; ++i) {
    SAMP_CHECK(std::isfinite(values[i])) << "ExtractSurface: value " << i << " is not finite";
    max_value = std::max(max_value, values[i]);
    below = below || values[i] < isovalue;
  }
  if (!below) return Mesh();  // nothing inside

  const float background = std::max<float>(max_value, float(isovalue + grid.voxel_size));
  auto vdb = openvdb::FloatGrid::create(background);
  auto transform = openvdb::math::Transform::createLinearTransform(grid.voxel_size);
  transform->postTranslate(openvdb::Vec3d(grid.origin.x(), grid.origin.y(), grid.origin.z()));
  vdb->setTransform(transform);
  {
    auto accessor = vdb->getAccessor();
    for (int k = 0; k < grid.dims.z(); ++k) {
      for (int j = 0; j < grid.dims.y(); ++j) {
        for (int i = 0; i < grid.dims.x(); ++i) {
          accessor.setValue(openvdb::Coord(i, j, k), values[grid.Index(i, j, k)]);
        }
      }
    }
  }

  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*vdb, points, triangles, quads, isovalue, /*adaptivity=*/0.0);

  Mesh mesh;
  mesh.vertices.reserve(points.size());
  for (const auto& p : points) mesh.vertices.emplace_back(p.x(), p.y(), p.z());
  mesh.triangles.reserve(triangles.size() + 2 * quads.size());
  // OpenVDB's polygons are counter-clockwise seen from outside (towards larger
  // values), as samp's meshes are.
  for (const auto& t : triangles) mesh.triangles.emplace_back(int(t[0]), int(t[1]), int(t[2]));
  for (const auto& q : quads) {
    // Split along the shorter diagonal for better-shaped triangles.
    const Eigen::Vector3f a = mesh.vertices[q[0]], b = mesh.vertices[q[1]],
                          c = mesh.vertices[q[2]], d = mesh.vertices[q[3]];
    if ((a - c).squaredNorm() <= (b - d).squaredNorm()) {
      mesh.triangles.emplace_back(int(q[0]), int(q[1]), int(q[2]));
      mesh.triangles.emplace_back(int(q[0]), int(q[2]), int(q[3]));
    } else {
      mesh.triangles.emplace_back(int(q[0]), int(q[1]), int(q[3]));
      mesh.triangles.emplace_back(int(q[1]), int(q[2]), int(q[3]));
    }
  }
  return mesh;
}

}  // namespace

Mesh ExtractSurface(const GridSpec& grid, const std::vector<float>& values, double isovalue) {
  return ExtractSurfaceImpl(grid, values.data(), int64_t(values.size()), isovalue);
}

Mesh ExtractSurface(const GridSpec& grid, const Eigen::VectorXf& values, double isovalue) {
  return ExtractSurfaceImpl(grid, values.data(), int64_t(values.size()), isovalue);
}

double SignedVolume(const Mesh& mesh) {
  double volume = 0.0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[t[1]].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[t[2]].cast<double>();
    volume += a.dot(b.cross(c));
  }
  return volume / 6.0;
}

}  // namespace samp
