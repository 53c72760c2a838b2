// RAII wrappers around Embree 3 devices and scenes. An error callback turns
// every Embree error into a samp::Error. A committed scene is safe to query
// from many threads at once.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "libsamp/core/camera.h"
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
  // Casts one ray per pixel centre of `camera` for the image rows [row_begin,
  // row_end), in coherent square tiles (the fastest path). Pixel (u, v) has its
  // centre at integer coordinates (OpenCV/KITTI convention): the ray direction in
  // the camera is normalize(camera.Ray(u, v)), in the scene world_from_camera.linear()
  // times that. Writes hits[(v - row_begin) * width + u]; `hits` must hold
  // (row_end - row_begin) * width entries. Thread-safe.
  void IntersectCamera(const PinholeCamera& camera, const Eigen::Isometry3d& world_from_camera,
                       int row_begin, int row_end, RayHit* hits) const;

  // Image outputs of IntersectCameraImage; null pointers are not written. Each
  // points at (row_end - row_begin) * width entries, row-major from row_begin.
  struct ImageOutputs {
    float* depth = nullptr;             // z in the camera, inf = miss
    int32_t* geometry = nullptr;        // mesh index, -1 = miss
    int32_t* triangle = nullptr;        // triangle index within the mesh, -1 = miss
    Eigen::Vector3f* normal = nullptr;  // unit geometric normal in the scene frame, facing
                                        // the camera; zero = miss
  };
  // Same rays as IntersectCamera, written straight into image buffers (the
  // scanner's and renderer's path: no intermediate RayHit per pixel). Thread-safe.
  void IntersectCameraImage(const PinholeCamera& camera, const Eigen::Isometry3d& world_from_camera,
                            int row_begin, int row_end, const ImageOutputs& outputs) const;

  // Number of rays per Embree packet used (16, 8 or 4, the widest the CPU runs natively).
  int PacketSize() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace samp
