// RAII wrappers around Embree 3 devices and scenes. An error callback turns
// every Embree error into a samp::Error. A committed scene is safe to query
// from many threads at once.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "libsamp/core/mesh.h"

namespace samp {

struct RayHit {
  float t = std::numeric_limits<float>::infinity();  // distance along the (unit) direction; inf = miss
  int geometry = -1;                                  // index of the mesh in the scene
  int triangle = -1;                                  // triangle index within that mesh
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();   // unit geometric normal, facing the ray origin
  bool Hit() const { return geometry >= 0; }
};

class EmbreeScene {
 public:
  // Builds and commits a scene over `meshes` (geometry ids = indices). The
  // meshes are copied; the scene does not reference them afterwards.
  explicit EmbreeScene(const std::vector<const Mesh*>& meshes);
  explicit EmbreeScene(const Mesh& mesh) : EmbreeScene(std::vector<const Mesh*>{&mesh}) {}
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  // Casts rays (unit directions) in packets; `hits` is resized to origins.size().
  void Intersect(const std::vector<Eigen::Vector3f>& origins,
                 const std::vector<Eigen::Vector3f>& directions, std::vector<RayHit>* hits,
                 float t_far = std::numeric_limits<float>::infinity()) const;
  // Casts all rays of one pinhole camera from a common origin (faster path).
  // `directions` row-major per pixel, unit length. Same output as Intersect.
  void IntersectFromOrigin(const Eigen::Vector3f& origin,
                           const std::vector<Eigen::Vector3f>& directions,
                           std::vector<RayHit>* hits) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace samp
