#include "libsamp/scan/scanner.h"

#include <cmath>
#include <limits>

#include "libsamp/core/error.h"
#include "libsamp/scan/embree_scene.h"
#include "libsamp/scan/scan_option_table.h"

namespace samp {

void ScanOptions::Check() const { ScanOptionTable().Check(*this); }

std::vector<Eigen::Vector3d> FibonacciSphere(int n) {
  SAMP_CHECK(n >= 1) << "FibonacciSphere: n must be >= 1, got " << n;
  // Equal-area latitude bands z_i = 1 - (2i + 1) / n, longitudes stepped by the golden angle.
  const double golden_angle = M_PI * (3.0 - std::sqrt(5.0));
  std::vector<Eigen::Vector3d> directions(n);
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden_angle * i;
    directions[i] = Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z);
  }
  return directions;
}

namespace {

// A camera at `eye` looking at `target`. The image's down direction (camera y)
// is the object's +y (down in the canonical frame) projected onto the image
// plane, so cars appear upright; within ~8 degrees of the vertical the object's
// +z serves as reference instead (a deterministic, continuous-enough choice).
Eigen::Isometry3d LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - eye).normalized();
  Eigen::Vector3d reference = Eigen::Vector3d::UnitY();
  if (std::abs(z.dot(reference)) > 0.99) reference = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d x = reference.cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d object_from_camera = Eigen::Isometry3d::Identity();
  object_from_camera.linear().col(0) = x;
  object_from_camera.linear().col(1) = y;
  object_from_camera.linear().col(2) = z;
  object_from_camera.translation() = eye;
  return object_from_camera;
}

}  // namespace

ScanResult ScanMesh(const Mesh& mesh, const ScanOptions& options) {
  ScanResult result;
  ScanMesh(mesh, options, &result);
  return result;
}

void ScanMesh(const Mesh& mesh, const ScanOptions& options, ScanResult* result) {
  options.Check();
  SAMP_CHECK(!mesh.Empty()) << "ScanMesh: the mesh is empty";
  const AlignedBox box = mesh.Bounds();
  const Eigen::Vector3d center = box.Center();
  const double radius = 0.5 * box.Size().norm();
  SAMP_CHECK(std::isfinite(radius) && radius > 0) << "ScanMesh: the mesh has zero extent";

  const EmbreeScene scene(mesh);

  PinholeCamera camera;
  camera.width = options.width;
  camera.height = options.height;
  // The field of view spans the smaller image side.
  const double focal =
      0.5 * std::min(options.width, options.height) / std::tan(0.5 * options.fov_deg * M_PI / 180.0);
  camera.fx = camera.fy = focal;
  camera.cx = 0.5 * (options.width - 1);
  camera.cy = 0.5 * (options.height - 1);

  result->triangle_seen.assign(mesh.triangles.size(), 0);
  result->num_rays = result->num_hits = 0;
  result->views.resize(options.num_views);  // kept views keep their images' capacity
  const int64_t num_pixels = int64_t(options.width) * options.height;
  const double distance = options.distance_factor * radius;
  const std::vector<Eigen::Vector3d> directions = FibonacciSphere(options.num_views);
  for (int index = 0; index < options.num_views; ++index) {
    const Eigen::Isometry3d object_from_camera = LookAt(center + distance * directions[index], center);
    ScanView& view = result->views[index];
    view.camera = camera;
    view.camera_from_object = object_from_camera.inverse();
    view.depth.resize(num_pixels);  // every pixel is written below
    view.triangle.resize(num_pixels);
    EmbreeScene::ImageOutputs outputs;
    outputs.depth = view.depth.data();
    outputs.triangle = view.triangle.data();
    scene.IntersectCameraImage(camera, object_from_camera, 0, options.height, outputs);
    for (const int32_t triangle : view.triangle) {
      if (triangle < 0) continue;
      result->triangle_seen[triangle] = 1;
      ++result->num_hits;
    }
    result->num_rays += num_pixels;
  }
}

PointCloud ScanResult::SurfacePoints() const {
  PointCloud cloud;
  cloud.points.reserve(size_t(num_hits));
  for (const ScanView& view : views) {
    const PinholeCamera& camera = view.camera;
    const Eigen::Isometry3d object_from_camera = view.camera_from_object.inverse();
    const Eigen::Matrix3f rotation = object_from_camera.linear().cast<float>();
    const Eigen::Vector3f translation = object_from_camera.translation().cast<float>();
    const float inv_fx = float(1.0 / camera.fx), inv_fy = float(1.0 / camera.fy);
    for (int v = 0; v < camera.height; ++v) {
      for (int u = 0; u < camera.width; ++u) {
        const float depth = view.depth[int64_t(v) * camera.width + u];
        if (!std::isfinite(depth)) continue;
        const Eigen::Vector3f point_in_camera(depth * (float(u) - float(camera.cx)) * inv_fx,
                                              depth * (float(v) - float(camera.cy)) * inv_fy, depth);
        cloud.points.push_back(rotation * point_in_camera + translation);
      }
    }
  }
  return cloud;
}

}  // namespace samp
