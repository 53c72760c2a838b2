#include "libsamp/synth/shading.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "libsamp/core/error.h"
#include "libsamp/synth/procedural.h"

namespace samp::synth {
namespace {

using procedural::Mix;

// What ShadeView knows of one view.
struct View {
  const ShadingPreset& preset;
  const SynthOptions& options;
  const Scene& scene;
  int num_statics = 0;
  std::vector<Eigen::Isometry3d> object_from_world;  // per car, of this frame
};

// The surface point and normal (world frame) of a hit pixel. kWorld: kept in
// float for every pixel (zero normal where nothing was hit), as the shadow
// rays take them, and shaded at exactly those values; kCamera: computed per
// pixel in double.
class SurfaceSamples {
 public:
  SurfaceSamples(const ShadingPreset& preset, const Eigen::Isometry3d& world_from_camera,
                 const PinholeCamera& camera, const RenderBuffers& buffers)
      : world_(preset.buffers == ShadingPreset::BufferFrame::kWorld),
        world_from_camera_(world_from_camera),
        rotation_(world_from_camera.linear()),
        camera_(camera),
        buffers_(buffers) {
    if (!world_) return;
    const size_t num_pixels = size_t(camera.width) * camera.height;
    points_.resize(num_pixels);
    normals_.assign(num_pixels, Eigen::Vector3f::Zero());
    tbb::parallel_for(0, camera.height, [&](int v) {
      for (int u = 0; u < camera.width; ++u) {
        const size_t pixel = size_t(v) * camera.width + u;
        if (buffers.mesh_index[pixel] < 0) continue;
        points_[pixel] = (world_from_camera * (camera.Ray(u, v) * double(buffers.depth[pixel]))).cast<float>();
        normals_[pixel] = buffers.normal[pixel];
      }
    });
  }

  void At(int u, int v, Eigen::Vector3d* point, Eigen::Vector3d* normal) const {
    const size_t pixel = size_t(v) * camera_.width + u;
    if (world_) {
      *point = points_[pixel].cast<double>();
      *normal = normals_[pixel].cast<double>();
    } else {
      *point = world_from_camera_ * (camera_.Ray(u, v) * double(buffers_.depth[pixel]));
      *normal = rotation_ * buffers_.normal[pixel].cast<double>();
    }
  }

  // 1 where the sun is seen from the surface point (everywhere without shadows).
  std::vector<uint8_t> SunVisibility(const ShadingPreset& preset, const Scene& scene,
                                     const EmbreeScene* embree) const {
    if (!preset.shadows) return std::vector<uint8_t>(size_t(camera_.width) * camera_.height, 1);
    SAMP_CHECK(embree != nullptr && world_) << "synth: shadows need the world-frame scene";
    return LightVisibility(*embree, points_, normals_, scene.lighting.to_sun.cast<float>(), 0.01f);
  }

 private:
  bool world_;
  const Eigen::Isometry3d& world_from_camera_;
  const Eigen::Matrix3d rotation_;
  const PinholeCamera& camera_;
  const RenderBuffers& buffers_;
  std::vector<Eigen::Vector3f> points_, normals_;  // kWorld only
};

// kPlain: flat paint; tyres, bumpers and underbody dark below 0.30 m; dark windows.
SurfaceMaterial PlainCarMaterial(const SceneCar& car, const Eigen::Vector3d& p_object,
                                 const Eigen::Vector3d& normal) {
  SurfaceMaterial material;
  material.albedo = car.paint;
  material.specular = 0.35;
  material.shininess = 40.0;
  if (p_object.y() > -0.30) {
    material.albedo = Eigen::Vector3d(0.04, 0.04, 0.045);
    material.specular = 0.05;
  } else if (p_object.y() < -0.62 * car.height && normal.y() > -0.9) {
    material.albedo = Eigen::Vector3d(0.06, 0.07, 0.09);
    material.specular = 0.6;
  }
  return material;
}

// kClearCoat: tyres (the synthesised wheel triangles) with a grey rim, dark
// bumpers, sills and underbody, tinted glass, textured paint under a clear coat.
SurfaceMaterial ClearCoatCarMaterial(const SynthOptions& options, const SceneCar& car,
                                     const Eigen::Vector3d& p_object, const Eigen::Vector3d& n_object,
                                     int triangle, double footprint) {
  SurfaceMaterial material;
  const int body_triangles = car.car->num_body_triangles;
  if (body_triangles >= 0 && triangle >= body_triangles) {
    // The rim: the part facing sideways towards the hub, away from the tread.
    const bool rim = std::abs(n_object.z()) > 0.8 && p_object.y() < -0.12 && p_object.y() > -0.55;
    material.albedo = rim ? Eigen::Vector3d(0.35, 0.35, 0.36) : Eigen::Vector3d(0.03, 0.03, 0.03);
    material.specular = rim ? 0.3 : 0.02;
    material.shininess = 20.0;
  } else if (p_object.y() > -0.28) {  // bumpers, sills, underbody, open wheel arches
    material.albedo = Eigen::Vector3d(0.035, 0.035, 0.04);
    material.specular = 0.05;
    material.shininess = 20.0;
  } else if (p_object.y() < -0.62 * car.height && std::abs(n_object.y()) < 0.85) {  // windows
    // Tinted glass; what lies behind it (seats, headrests, the far windows) is
    // drawn on the glass plane as a blotchy grey of mean window_interior_albedo.
    const double interior = procedural::Fractal(p_object, 5.0, 4, footprint, Mix(uint64_t(car.track_id), 91));
    material.albedo = Eigen::Vector3d(0.02, 0.025, 0.03) +
                      Eigen::Vector3d::Constant(options.window_interior_albedo * std::max(0.0, 1.0 + 2.5 * interior));
    material.specular = 1.2;
    material.shininess = 250.0;
    material.fresnel_f0 = options.glass_fresnel_f0;
  } else {  // paint: weak texture (dirt, orange peel) under a clear coat
    const double grain = procedural::Fractal(p_object, 6.0, 4, footprint, Mix(uint64_t(car.track_id), 77));
    material.albedo = car.paint * (1.0 + 2.0 * options.paint_texture * grain);
    material.specular = options.paint_specular * (car.metallic ? 1.3 : 1.0);
    material.shininess = car.metallic ? 0.5 * options.paint_shininess : options.paint_shininess;
    material.fresnel_f0 = options.paint_fresnel_f0;
  }
  return material;
}

// A street object's material; on the asphalt a contact shadow under the cars
// (sky light blocked) fading over 0.5 m outside their footprints.
SurfaceMaterial StreetObjectMaterial(const View& view, const StaticMesh& m, const Eigen::Vector3d& point,
                               const Eigen::Vector3d& normal, double footprint, double* occlusion) {
  const StreetObject& object = view.scene.street_objects[m.street_index];
  SurfaceMaterial material;
  material.albedo = StreetAlbedo(object, view.scene.layout, point, normal, footprint);
  if (object.material == StreetMaterial::kPole || object.material == StreetMaterial::kSign) {
    material.specular = 0.3;
    material.shininess = 30.0;
  }
  if (object.material == StreetMaterial::kAsphalt) {
    for (size_t c = 0; c < view.scene.cars.size(); ++c) {
      const Eigen::Vector3d q = view.object_from_world[c] * point;
      const double ox = std::abs(q.x()) - 0.5 * view.scene.cars[c].length;
      const double oz = std::abs(q.z()) - 0.5 * view.scene.cars[c].width;
      const double outside = std::max(ox, oz);
      if (outside < 0.5) *occlusion = std::min(*occlusion, 0.25 + 0.75 * std::clamp(outside / 0.5, 0.0, 1.0));
    }
  }
  return material;
}

// The material of a static mesh by its kind: the clean preset's road, facades
// (windows on the walls, blotches on the tops) and blotchy boxes, or a street object.
SurfaceMaterial StaticMaterial(const View& view, const StaticMesh& m, const Eigen::Vector3d& point,
                               const Eigen::Vector3d& normal, double footprint, double* occlusion) {
  SurfaceMaterial material;
  switch (m.material) {
    case MaterialKind::kStreet:
      return StreetObjectMaterial(view, m, point, normal, footprint, occlusion);
    case MaterialKind::kRoad:
      material.albedo = procedural::RoadAlbedo(point, kRoadHalfWidth, kLaneWidth, footprint, m.seed);
      break;
    case MaterialKind::kFacade:
      if (std::abs(normal.y()) > 0.7) {
        material.albedo = procedural::BlotchAlbedo(point, m.color, footprint, m.seed);
      } else {
        const double along = std::abs(normal.x()) > std::abs(normal.z()) ? point.z() : point.x();
        material.albedo = procedural::FacadeAlbedo(along, view.options.camera_height - point.y(), m.color,
                                                   footprint, m.seed);
      }
      break;
    case MaterialKind::kBlotch:
      material.albedo = procedural::BlotchAlbedo(point, m.color, footprint, m.seed);
      break;
  }
  return material;
}

// kLambert light: albedo (ambient + diffuse max(0, n.s)) + a white highlight.
Eigen::Vector3d LambertRadiance(const ShadingPreset& preset, const OutdoorLighting& lighting,
                                const SurfaceMaterial& material, double ambient, const Eigen::Vector3d& normal,
                                const Eigen::Vector3d& to_viewer) {
  const double diffuse = std::max(0.0, normal.dot(lighting.to_sun));
  Eigen::Vector3d radiance = material.albedo * (ambient + preset.diffuse * diffuse);
  if (material.specular > 0.0) {
    const Eigen::Vector3d half = (lighting.to_sun + to_viewer).normalized();
    const double specular = material.specular * std::pow(std::max(0.0, normal.dot(half)), material.shininess);
    radiance += Eigen::Vector3d::Constant(specular);
  }
  return radiance;
}

// Radiance of a hit pixel towards the camera.
Eigen::Vector3d SurfaceRadiance(const View& view, const RenderBuffers& buffers, size_t pixel,
                                const Eigen::Vector3d& point, const Eigen::Vector3d& normal,
                                const Eigen::Vector3d& to_viewer, double footprint, double sun_visible) {
  const int index = buffers.mesh_index[pixel];
  const bool is_car = index >= view.num_statics;
  SurfaceMaterial material;
  double occlusion = 1.0;
  if (is_car) {
    const int c = index - view.num_statics;
    const SceneCar& car = view.scene.cars[c];
    const Eigen::Vector3d p_object = view.object_from_world[c] * point;
    if (view.preset.car_finish == ShadingPreset::CarFinish::kPlain) {
      material = PlainCarMaterial(car, p_object, normal);
    } else {
      const Eigen::Vector3d n_object = view.object_from_world[c].linear() * normal;
      material = ClearCoatCarMaterial(view.options, car, p_object, n_object, buffers.triangle[pixel], footprint);
    }
  } else {
    material = StaticMaterial(view, view.scene.statics[index], point, normal, footprint, &occlusion);
  }
  if (view.preset.light == ShadingPreset::Light::kOutdoor) {
    return ShadeSurface(material, normal, to_viewer, view.scene.lighting, sun_visible, occlusion);
  }
  const double ambient = is_car ? view.preset.car_ambient : view.preset.static_ambient;
  return LambertRadiance(view.preset, view.scene.lighting, material, ambient, normal, to_viewer);
}

}  // namespace

ShadingPreset CleanShading() { return ShadingPreset(); }

ShadingPreset StreetShading(const SynthOptions& options) {
  ShadingPreset preset;
  preset.buffers = ShadingPreset::BufferFrame::kWorld;
  preset.sky = ShadingPreset::Sky::kEnvironment;
  preset.light = ShadingPreset::Light::kOutdoor;
  preset.car_finish = ShadingPreset::CarFinish::kClearCoat;
  preset.shadows = options.shadows;
  return preset;
}

cv::Mat ShadeView(const ShadingPreset& preset, const SynthOptions& options, const Scene& scene, int frame,
                  const Eigen::Isometry3d& world_from_camera, const PinholeCamera& camera,
                  const RenderBuffers& buffers, const EmbreeScene* embree, uint64_t noise_seed) {
  View view{preset, options, scene, int(scene.statics.size()), {}};
  for (const SceneCar& car : scene.cars) view.object_from_world.push_back(WorldFromObject(car.states[frame]).inverse());
  const SurfaceSamples surface(preset, world_from_camera, camera, buffers);
  const std::vector<uint8_t> sun_visible = surface.SunVisibility(preset, scene, embree);
  const Eigen::Matrix3d rotation = world_from_camera.linear();
  cv::Mat image(camera.height, camera.width, CV_8UC3);
  tbb::parallel_for(0, camera.height, [&](int v) {
    std::mt19937_64 noise_engine(Mix(noise_seed, uint64_t(v)));
    std::normal_distribution<double> noise(0.0, 1.0);
    for (int u = 0; u < camera.width; ++u) {
      const size_t pixel = size_t(v) * camera.width + u;
      const Eigen::Vector3d ray = camera.Ray(u, v);
      const Eigen::Vector3d to_viewer = -(rotation * ray.normalized());
      Eigen::Vector3d radiance;
      if (buffers.mesh_index[pixel] < 0) {
        radiance = preset.sky == ShadingPreset::Sky::kEnvironment
                       ? scene.lighting.Environment(-to_viewer)
                       : Eigen::Vector3d(Eigen::Vector3d(0.70, 0.80, 0.95) * (1.0 - 0.25 * double(v) / camera.height));
      } else {
        Eigen::Vector3d point, normal;
        surface.At(u, v, &point, &normal);
        const double cos_incidence = std::max(0.2, std::abs(normal.dot(to_viewer)));
        const double footprint = buffers.depth[pixel] * ray.norm() / camera.fx / cos_incidence;
        radiance = SurfaceRadiance(view, buffers, pixel, point, normal, to_viewer, footprint, sun_visible[pixel]);
      }
      cv::Vec3b& out = image.at<cv::Vec3b>(v, u);
      for (int c = 0; c < 3; ++c) {
        const double value = 255.0 * std::pow(std::clamp(scene.exposure * radiance[c], 0.0, 1.0), 1.0 / 2.2) +
                             options.image_noise_sigma * noise(noise_engine);
        out[2 - c] = cv::saturate_cast<uint8_t>(std::lround(value));
      }
    }
  });
  return image;
}

}  // namespace samp::synth
