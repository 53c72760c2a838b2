#include "libsamp/scan/renderer.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "libsamp/core/error.h"
#include "libsamp/scan/embree_scene.h"

namespace samp {

RenderBuffers Render(const PinholeCamera& camera, const std::vector<PlacedMesh>& meshes) {
  SAMP_CHECK(camera.width > 0 && camera.height > 0 && camera.fx > 0 && camera.fy > 0)
      << "Render: invalid camera (" << camera.width << "x" << camera.height << ", fx " << camera.fx
      << ", fy " << camera.fy << ")";
  // The scene is built in the camera frame, so rays start at the origin and
  // normals come out in the camera frame directly.
  std::vector<Mesh> meshes_in_camera(meshes.size());
  std::vector<const Mesh*> scene_meshes(meshes.size(), nullptr);
  for (size_t i = 0; i < meshes.size(); ++i) {
    if (meshes[i].mesh == nullptr || meshes[i].mesh->Empty()) continue;
    meshes_in_camera[i] = *meshes[i].mesh;
    meshes_in_camera[i].Transform(Eigen::Affine3d(meshes[i].camera_from_object));
    scene_meshes[i] = &meshes_in_camera[i];
  }
  const EmbreeScene scene(scene_meshes);
  return RenderFromScene(scene, camera, Eigen::Isometry3d::Identity());
}

std::vector<uint8_t> ShadeRender(const RenderBuffers& buffers,
                                 const std::vector<Eigen::Vector3f>& colors) {
  const size_t num_pixels = size_t(buffers.width) * buffers.height;
  SAMP_CHECK(buffers.depth.size() == num_pixels && buffers.mesh_index.size() == num_pixels &&
             buffers.normal.size() == num_pixels)
      << "ShadeRender: buffers do not match their size " << buffers.width << "x" << buffers.height;
  // Headlight along the viewing axis plus a key light from above-left-behind the
  // camera (camera frame: x right, y down, z forward; vectors point to the light).
  const Eigen::Vector3f headlight(0.f, 0.f, -1.f);
  const Eigen::Vector3f key_light = Eigen::Vector3f(-0.4f, -0.8f, -0.45f).normalized();
  constexpr float kAmbient = 0.2f, kHeadlight = 0.55f, kKey = 0.35f;
  const Eigen::Vector3f default_color(0.7f, 0.7f, 0.7f);
  std::vector<uint8_t> rgb(3 * num_pixels, 255);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, num_pixels, 4096),
                    [&](const tbb::blocked_range<size_t>& range) {
                      for (size_t i = range.begin(); i != range.end(); ++i) {
                        const int index = buffers.mesh_index[i];
                        if (index < 0) continue;
                        const Eigen::Vector3f& n = buffers.normal[i];
                        const float light = kAmbient + kHeadlight * std::max(0.f, n.dot(headlight)) +
                                            kKey * std::max(0.f, n.dot(key_light));
                        const Eigen::Vector3f& base =
                            size_t(index) < colors.size() ? colors[index] : default_color;
                        for (int c = 0; c < 3; ++c) {
                          const float value = std::clamp(base[c] * light, 0.f, 1.f);
                          rgb[3 * i + c] = uint8_t(std::lround(255.f * value));
                        }
                      }
                    });
  return rgb;
}

RenderBuffers RenderFromScene(const EmbreeScene& scene, const PinholeCamera& camera,
                              const Eigen::Isometry3d& world_from_camera) {
  SAMP_CHECK(camera.width > 0 && camera.height > 0 && camera.fx > 0 && camera.fy > 0)
      << "RenderFromScene: invalid camera (" << camera.width << "x" << camera.height << ")";
  RenderBuffers buffers;
  buffers.width = camera.width;
  buffers.height = camera.height;
  const size_t num_pixels = size_t(camera.width) * camera.height;
  buffers.depth.resize(num_pixels);
  buffers.mesh_index.resize(num_pixels);
  buffers.triangle.resize(num_pixels);
  buffers.normal.resize(num_pixels);

  // Bands of rows (a multiple of the packet tile height) in parallel.
  constexpr int kBandRows = 8;
  const int num_bands = (camera.height + kBandRows - 1) / kBandRows;
  tbb::parallel_for(tbb::blocked_range<int>(0, num_bands), [&](const tbb::blocked_range<int>& range) {
    for (int band = range.begin(); band != range.end(); ++band) {
      const int row_begin = band * kBandRows;
      const int row_end = std::min(camera.height, row_begin + kBandRows);
      const size_t offset = size_t(row_begin) * camera.width;
      EmbreeScene::ImageOutputs outputs;
      outputs.depth = buffers.depth.data() + offset;
      outputs.geometry = buffers.mesh_index.data() + offset;
      outputs.triangle = buffers.triangle.data() + offset;
      outputs.normal = buffers.normal.data() + offset;
      scene.IntersectCameraImage(camera, world_from_camera, row_begin, row_end, outputs);
    }
  });
  return buffers;
}

std::vector<uint8_t> LightVisibility(const EmbreeScene& scene, const std::vector<Eigen::Vector3f>& points,
                                     const std::vector<Eigen::Vector3f>& normals,
                                     const Eigen::Vector3f& to_light, float bias, float max_distance) {
  SAMP_CHECK(points.size() == normals.size()) << "LightVisibility: " << points.size() << " points but "
                                              << normals.size() << " normals";
  std::vector<uint8_t> visible(points.size(), 0);
  constexpr size_t kChunk = 4096;
  const size_t num_chunks = (points.size() + kChunk - 1) / kChunk;
  tbb::parallel_for(size_t(0), num_chunks, [&](size_t chunk) {
    const size_t begin = chunk * kChunk, end = std::min(points.size(), begin + kChunk);
    std::vector<Eigen::Vector3f> origins, directions;
    std::vector<size_t> index;
    origins.reserve(end - begin);
    for (size_t i = begin; i < end; ++i) {
      if (normals[i].squaredNorm() == 0.f) continue;
      origins.push_back(points[i] + bias * (to_light + normals[i]));
      directions.push_back(to_light);
      index.push_back(i);
    }
    std::vector<RayHit> hits;
    scene.Intersect(origins, directions, &hits, max_distance);
    for (size_t k = 0; k < index.size(); ++k) visible[index[k]] = hits[k].Hit() ? 0 : 1;
  });
  return visible;
}

Eigen::Vector3d OutdoorLighting::Environment(const Eigen::Vector3d& direction) const {
  const double up = -direction.y();  // y points down
  if (up < 0.0) return ground;
  const double t = std::pow(std::clamp(up, 0.0, 1.0), 0.5);
  return (1.0 - t) * horizon + t * zenith;
}

Eigen::Vector3d ShadeSurface(const SurfaceMaterial& material, const Eigen::Vector3d& normal,
                             const Eigen::Vector3d& to_viewer, const OutdoorLighting& lighting,
                             double sun_visible, double occlusion) {
  const double n_dot_v = std::clamp(normal.dot(to_viewer), 0.0, 1.0);
  const double fresnel =
      material.fresnel_f0 > 0.0 ? material.fresnel_f0 + (1.0 - material.fresnel_f0) * std::pow(1.0 - n_dot_v, 5.0)
                                : 0.0;
  const double n_dot_s = std::max(0.0, normal.dot(lighting.to_sun));
  Eigen::Vector3d radiance = (1.0 - fresnel) * material.albedo.cwiseProduct(
                                                    lighting.ambient * occlusion + lighting.sun * (sun_visible * n_dot_s));
  if (material.specular > 0.0 && sun_visible > 0.0 && n_dot_s > 0.0) {
    const Eigen::Vector3d half = (lighting.to_sun + to_viewer).normalized();
    radiance += material.specular * sun_visible * std::pow(std::max(0.0, normal.dot(half)), material.shininess) *
                lighting.sun;
  }
  if (fresnel > 0.0) {
    const Eigen::Vector3d reflected = 2.0 * n_dot_v * normal - to_viewer;
    radiance += fresnel * occlusion * lighting.Environment(reflected.normalized());
  }
  return radiance;
}

}  // namespace samp
