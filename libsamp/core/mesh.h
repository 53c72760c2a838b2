// Triangle meshes and point clouds in memory. Plain data; not thread-safe to
// mutate concurrently, safe to read from many threads.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

namespace samp {

struct AlignedBox {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d max = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  bool IsEmpty() const { return !(min.array() <= max.array()).all(); }
  void Extend(const Eigen::Vector3d& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  Eigen::Vector3d Size() const { return IsEmpty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(max - min); }
  Eigen::Vector3d Center() const { return 0.5 * (min + max); }
};

struct Mesh {
  std::vector<Eigen::Vector3f> vertices;
  // Vertex indices per triangle.
  std::vector<Eigen::Vector3i> triangles;

  bool Empty() const { return vertices.empty() || triangles.empty(); }
  // Bounding box of the vertices referenced by triangles.
  AlignedBox Bounds() const;
  // Applies p -> transform * p to every vertex.
  void Transform(const Eigen::Affine3d& transform);
  // Appends another mesh (indices shifted).
  void Append(const Mesh& other);
  // Per-triangle unit normals (zero for degenerate triangles).
  std::vector<Eigen::Vector3f> TriangleNormals() const;
};

// Axis-aligned box as a closed 12-triangle mesh with outward-facing triangles.
Mesh MakeBoxMesh(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner);
// The rectangle [x0, x1] x [z0, z1] of the plane at height y as two triangles
// facing -y (up in the camera frame: a ground under a camera looking along z).
Mesh MakeGroundMesh(double y, double x0, double x1, double z0, double z1);
// Closed UV sphere (outward-facing), `rings` >= 3 latitude bands, `segments` >= 3.
Mesh MakeSphereMesh(const Eigen::Vector3d& center, double radius, int rings = 32, int segments = 64);

struct PointCloud {
  std::vector<Eigen::Vector3f> points;
  // Optional, empty or one RGB colour per point.
  std::vector<Eigen::Matrix<uint8_t, 3, 1>> colors;
};

}  // namespace samp
