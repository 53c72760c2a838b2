// Rendering scenes of meshes into a pinhole camera with Embree: per-pixel depth,
// which mesh and triangle, and the surface normal. Used for the synthetic
// benchmark, the evaluation's depth buffers and the inspector's pictures.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "libsamp/core/camera.h"
#include "libsamp/core/mesh.h"

namespace samp {

// One mesh placed in the camera frame: point_in_camera = camera_from_object * point.
struct PlacedMesh {
  const Mesh* mesh = nullptr;
  Eigen::Isometry3d camera_from_object = Eigen::Isometry3d::Identity();
};

struct RenderBuffers {
  int width = 0, height = 0;
  std::vector<float> depth;              // z in the camera, inf where nothing was hit
  std::vector<int32_t> mesh_index;       // index into the meshes passed, -1 = none
  std::vector<int32_t> triangle;         // triangle within that mesh, -1 = none
  std::vector<Eigen::Vector3f> normal;   // unit normal in the camera frame, facing the camera
  float Depth(int u, int v) const { return depth[size_t(v) * width + u]; }
};

// Renders `meshes` with one ray per pixel centre. Rows are processed in parallel (TBB).
RenderBuffers Render(const PinholeCamera& camera, const std::vector<PlacedMesh>& meshes);

// Simple headlight + key-light Lambert shading of a render into an 8-bit RGB
// image (row-major, 3 bytes per pixel), `colors` one per mesh, background white.
std::vector<uint8_t> ShadeRender(const RenderBuffers& buffers,
                                 const std::vector<Eigen::Vector3f>& colors);

}  // namespace samp
