#include "libsamp/core/mesh.h"

#include <cmath>

#include "libsamp/core/error.h"

namespace samp {

AlignedBox Mesh::Bounds() const {
  AlignedBox box;
  for (const Eigen::Vector3i& t : triangles) {
    for (int c = 0; c < 3; ++c) box.Extend(vertices[t[c]].cast<double>());
  }
  return box;
}

void Mesh::Transform(const Eigen::Affine3d& transform) {
  const Eigen::Affine3f t = transform.cast<float>();
  for (Eigen::Vector3f& v : vertices) v = t * v;
}

void Mesh::Append(const Mesh& other) {
  const int offset = int(vertices.size());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  triangles.reserve(triangles.size() + other.triangles.size());
  for (const Eigen::Vector3i& t : other.triangles) {
    triangles.push_back(t + Eigen::Vector3i::Constant(offset));
  }
}

std::vector<Eigen::Vector3f> Mesh::TriangleNormals() const {
  std::vector<Eigen::Vector3f> normals(triangles.size());
  for (size_t i = 0; i < triangles.size(); ++i) {
    const Eigen::Vector3i& t = triangles[i];
    Eigen::Vector3f n = (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]);
    const float norm = n.norm();
    normals[i] = norm > 0.f ? Eigen::Vector3f(n / norm) : Eigen::Vector3f::Zero();
  }
  return normals;
}

Mesh MakeGroundMesh(double y, double x0, double x1, double z0, double z1) {
  Mesh ground;
  ground.vertices = {Eigen::Vector3f(x0, y, z0), Eigen::Vector3f(x1, y, z0), Eigen::Vector3f(x1, y, z1),
                     Eigen::Vector3f(x0, y, z1)};
  ground.triangles = {Eigen::Vector3i(0, 2, 1), Eigen::Vector3i(0, 3, 2)};
  return ground;
}

Mesh MakeBoxMesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  Mesh mesh;
  for (int k = 0; k < 8; ++k) {
    mesh.vertices.emplace_back(float((k & 1) ? hi.x() : lo.x()), float((k & 2) ? hi.y() : lo.y()),
                               float((k & 4) ? hi.z() : lo.z()));
  }
  // Two triangles per face, counter-clockwise seen from outside.
  const int faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& f : faces) {
    mesh.triangles.emplace_back(f[0], f[1], f[2]);
    mesh.triangles.emplace_back(f[0], f[2], f[3]);
  }
  return mesh;
}

Mesh MakeSphereMesh(const Eigen::Vector3d& center, double radius, int rings, int segments) {
  SAMP_CHECK(rings >= 3 && segments >= 3) << "sphere needs rings >= 3 and segments >= 3";
  Mesh mesh;
  mesh.vertices.emplace_back(center.cast<float>() + Eigen::Vector3f(0, 0, float(radius)));
  for (int r = 1; r < rings; ++r) {
    const double theta = M_PI * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double phi = 2.0 * M_PI * s / segments;
      mesh.vertices.emplace_back(
          (center + radius * Eigen::Vector3d(std::sin(theta) * std::cos(phi),
                                             std::sin(theta) * std::sin(phi), std::cos(theta)))
              .cast<float>());
    }
  }
  mesh.vertices.emplace_back(center.cast<float>() - Eigen::Vector3f(0, 0, float(radius)));
  const int south = int(mesh.vertices.size()) - 1;
  auto ring_vertex = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) {
    mesh.triangles.emplace_back(0, ring_vertex(1, s), ring_vertex(1, s + 1));
    for (int r = 1; r < rings - 1; ++r) {
      const int a = ring_vertex(r, s), b = ring_vertex(r, s + 1);
      const int c = ring_vertex(r + 1, s), d = ring_vertex(r + 1, s + 1);
      mesh.triangles.emplace_back(a, c, d);
      mesh.triangles.emplace_back(a, d, b);
    }
    mesh.triangles.emplace_back(south, ring_vertex(rings - 1, s + 1), ring_vertex(rings - 1, s));
  }
  return mesh;
}

}  // namespace samp
