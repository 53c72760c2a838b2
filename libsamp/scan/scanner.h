// Virtual scanning of a mesh from many viewpoints (Fibonacci sphere) by ray
// casting with Embree, as the paper's training data: depth images and the
// surface points they see.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "libsamp/core/camera.h"
#include "libsamp/core/mesh.h"

namespace samp {

struct ScanOptions {
  // Number of viewpoints on a Fibonacci sphere around the mesh.
  int num_views = 100;
  // Image size of each view, pixels.
  int width = 400;
  int height = 400;
  // Field of view of each (square) view, degrees.
  double fov_deg = 40.0;
  // Camera distance to the bounding-box centre, as a multiple of the bounding-sphere radius
  // (the whole mesh is in view at the default field of view).
  double distance_factor = 3.2;

  void Check() const;
};

struct ScanView {
  PinholeCamera camera;
  Eigen::Isometry3d camera_from_object = Eigen::Isometry3d::Identity();
  // Per pixel (row-major, width*height): z depth in the camera (inf = no hit)
  // and the triangle hit (-1 = none).
  std::vector<float> depth;
  std::vector<int32_t> triangle;
};

struct ScanResult {
  std::vector<ScanView> views;
  // Per triangle of the scanned mesh: 1 if some ray of some view hit it.
  std::vector<uint8_t> triangle_seen;
  int64_t num_rays = 0;
  int64_t num_hits = 0;
  // All hit points in the object frame.
  PointCloud SurfacePoints() const;
};

// Fibonacci sphere of `n` unit directions (deterministic).
std::vector<Eigen::Vector3d> FibonacciSphere(int n);

// Scans `mesh` (object frame) from options.num_views viewpoints. Single-threaded
// per call; call it on different meshes from different threads.
ScanResult ScanMesh(const Mesh& mesh, const ScanOptions& options);
// The same scan into *result, reusing its buffers: the views' images (~128 MB
// at the default 100 views of 400 x 400) keep their capacity, so a loop over
// many meshes does not allocate them anew per mesh (fresh pages cost the
// kernel a fault and a zeroing each: 40 % of a training model's time,
// docs/benchmarks.md). Every field of *result is overwritten.
void ScanMesh(const Mesh& mesh, const ScanOptions& options, ScanResult* result);

}  // namespace samp
