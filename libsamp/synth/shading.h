// Shading of a rendered view into an 8-bit BGR image (internal to
// libsamp/synth): one path for both presets, the preset given as data.
//
// Per pixel: the surface point and normal in the world frame, the pixel's
// footprint on the surface, a material (albedo, highlight, Fresnel) from the
// scene (car finish by the preset; statics by their MaterialKind; the street's
// asphalt darkened under the cars by a contact shadow), the light
// model of the preset, then exposure, gamma 2.2 and Gaussian image noise. Where
// nothing was hit the preset's sky is seen.
#pragma once

#include <opencv2/core.hpp>

#include "libsamp/scan/renderer.h"
#include "libsamp/synth/scene.h"

namespace samp {
class EmbreeScene;
}

namespace samp::synth {

struct ShadingPreset {
  // The frame of the render buffers: kCamera (Render of the meshes placed in
  // the camera; normals in the camera frame) or kWorld (RenderFromScene of a
  // world-frame scene; normals in the world frame, and the surface points in
  // the Embree scene's float precision, where the shadow rays start).
  enum class BufferFrame { kCamera, kWorld } buffers = BufferFrame::kCamera;
  // Sky: a blue gradient darkening down the image rows, or the lighting's
  // environment seen along the pixel's ray.
  enum class Sky { kRowGradient, kEnvironment } sky = Sky::kRowGradient;
  // Light: kLambert: albedo (ambient + diffuse max(0, n.s)) plus a white
  // Blinn-Phong highlight of the material's strength, independent of the sun's
  // radiance; kOutdoor: ShadeSurface (renderer.h) with the scene's lighting.
  enum class Light { kLambert, kOutdoor } light = Light::kLambert;
  // Car finish: kPlain: flat paint, dark lower band (tyres, bumpers), dark
  // windows; kClearCoat: tyres with rims by triangle, textured paint under a
  // clear coat, tinted glass with the interior behind it.
  enum class CarFinish { kPlain, kClearCoat } car_finish = CarFinish::kPlain;
  // Sun shadows cast by everything (kWorld buffers and kOutdoor light only).
  bool shadows = false;
  // kLambert: ambient terms of cars and of the statics, and the diffuse weight.
  double car_ambient = 0.3, static_ambient = 0.4, diffuse = 0.7;
};

// The clean preset (Render in the camera, Lambert light, plain paint) and the
// street preset (RenderFromScene, outdoor light, clear coat, shadows as the
// options say).
ShadingPreset CleanShading();
ShadingPreset StreetShading(const SynthOptions& options);

// Shades the view of `buffers` (rendered at world_from_camera) of frame `frame`
// of `scene`. `embree` is the world-frame scene for the shadow rays (needed
// when preset.shadows, else unused and may be null). Rows in parallel, each
// with its own noise stream seeded by Mix(noise_seed, row): the result does not
// depend on the scheduling.
cv::Mat ShadeView(const ShadingPreset& preset, const SynthOptions& options, const Scene& scene, int frame,
                  const Eigen::Isometry3d& world_from_camera, const PinholeCamera& camera,
                  const RenderBuffers& buffers, const EmbreeScene* embree, uint64_t noise_seed);

}  // namespace samp::synth
