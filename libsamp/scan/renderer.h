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

class EmbreeScene;

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

// Renders a scene built once (e.g. in the world frame, for several cameras and
// shadow rays) for a pinhole camera at `world_from_camera` (scene frame <- camera).
// Depth is z in the camera; mesh_index is the scene's geometry index; normals are
// in the SCENE frame, facing the camera. Rows in parallel (TBB); thread-safe.
RenderBuffers RenderFromScene(const EmbreeScene& scene, const PinholeCamera& camera,
                              const Eigen::Isometry3d& world_from_camera);

// Visibility of a light in direction `to_light` (scene frame, unit) from each
// point: 1 when the segment from point + bias * (to_light + normal) towards the
// light hits nothing within max_distance, else 0. `points` and `normals` (unit,
// facing the viewer) are in the scene frame; entries with a zero normal are
// skipped (visibility 0). In parallel (TBB).
std::vector<uint8_t> LightVisibility(const EmbreeScene& scene, const std::vector<Eigen::Vector3f>& points,
                                     const std::vector<Eigen::Vector3f>& normals,
                                     const Eigen::Vector3f& to_light, float bias = 0.02f,
                                     float max_distance = 500.f);

// Outdoor lighting for ShadeSurface: a sun (direction and radiance) and a sky
// whose radiance is a gradient from the horizon to the zenith; below the horizon
// the environment is "ground". Directions in a frame with y pointing DOWN
// (KITTI world/camera), linear RGB radiance.
struct OutdoorLighting {
  Eigen::Vector3d to_sun = Eigen::Vector3d(-0.35, -1.0, -0.5).normalized();
  Eigen::Vector3d sun = Eigen::Vector3d(0.75, 0.72, 0.66);       // radiance of direct light
  Eigen::Vector3d ambient = Eigen::Vector3d(0.32, 0.34, 0.38);   // diffuse sky light on an open surface
  Eigen::Vector3d zenith = Eigen::Vector3d(0.30, 0.45, 0.80);
  Eigen::Vector3d horizon = Eigen::Vector3d(0.82, 0.86, 0.92);
  Eigen::Vector3d ground = Eigen::Vector3d(0.22, 0.21, 0.20);
  // Radiance of the environment seen in `direction` (unit, y down).
  Eigen::Vector3d Environment(const Eigen::Vector3d& direction) const;
};

// A surface: Lambert diffuse under a clear coat with a Blinn-Phong sun
// highlight and a Schlick-Fresnel mirror reflection of the environment.
struct SurfaceMaterial {
  Eigen::Vector3d albedo = Eigen::Vector3d::Constant(0.5);  // diffuse, linear RGB
  double specular = 0.0;     // strength of the sun highlight
  double shininess = 50.0;   // Blinn-Phong exponent
  double fresnel_f0 = 0.0;   // reflectance at normal incidence (paint/glass ~0.04); 0 = no reflection
};

// Outgoing radiance (linear RGB) towards the viewer:
//   F = f0 + (1 - f0) (1 - n.v)^5 (Schlick; 0 when f0 = 0),
//   L = (1 - F) albedo (ambient * occlusion + sun * sun_visible * max(0, n.s))
//       + specular * sun_visible * sun * max(0, n.h)^shininess + F * occlusion * Environment(reflect(-v, n)),
// n the unit normal, v towards the viewer, s towards the sun, h = normalize(s + v).
Eigen::Vector3d ShadeSurface(const SurfaceMaterial& material, const Eigen::Vector3d& normal,
                             const Eigen::Vector3d& to_viewer, const OutdoorLighting& lighting,
                             double sun_visible, double occlusion = 1.0);

}  // namespace samp
