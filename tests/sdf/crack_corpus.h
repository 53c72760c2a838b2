// A procedurally cracked test corpus (docs/sdf.md, "Cracked meshes"): clean
// closed meshes damaged the way real CAD folders are (deleted triangles,
// seams split with small gaps, vertex-clustering decimation, flipped and
// duplicated faces, interior parts), and the count of voxels whose sign
// differs from that of the clean original. Used by tests/sdf/sdf_test.cc and
// tests/bench/sdf_bench.cc. Deterministic: every random choice comes from the
// seed in CrackOptions.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "libsamp/core/grid_spec.h"
#include "libsamp/core/mesh.h"
#include "libsamp/core/wheels.h"

namespace samp {
namespace test {

struct CrackOptions {
  std::string name;
  double delete_fraction = 0.0;     // share of triangles deleted at random
  int num_seams = 0;                // planes across the body whose + side moves away ...
  double seam_gap = 0.0;            // ... by this many metres (a slit all around)
  double cluster_size = 0.0;        // vertex-clustering decimation cell, metres (0 = none)
  double flip_fraction = 0.0;       // share of triangles with reversed winding
  double duplicate_fraction = 0.0;  // share of triangles appended again (reversed)
  int num_interior_boxes = 0;       // closed boxes inside the inner half of the bounding box
  uint64_t seed = 1;
};

inline Eigen::Vector3f Centroid(const Mesh& mesh, const Eigen::Vector3i& t) {
  return (mesh.vertices[size_t(t[0])] + mesh.vertices[size_t(t[1])] + mesh.vertices[size_t(t[2])]) / 3.0f;
}

// Applies the damage of `options`, in the order: interior boxes, seams,
// decimation, deletion, flips, duplicates.
inline Mesh CrackMesh(const Mesh& clean, const CrackOptions& options) {
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Mesh mesh = clean;
  const AlignedBox box = clean.Bounds();
  const Eigen::Vector3d size = box.Size(), centre = box.Center();
  for (int b = 0; b < options.num_interior_boxes; ++b) {
    Eigen::Vector3d half, at;
    for (int a = 0; a < 3; ++a) {
      half[a] = size[a] * (0.05 + 0.07 * unit(rng));
      at[a] = centre[a] + size[a] * (unit(rng) - 0.5) * 0.3;
    }
    mesh.Append(MakeBoxMesh(at - half, at + half));
  }
  for (int s = 0; s < options.num_seams; ++s) {
    const int axis = (rng() % 2) ? 0 : 2;  // across the length or along the side
    const double offset = centre[axis] + size[axis] * (unit(rng) - 0.5) * 0.6;
    std::map<int, int> moved;  // old vertex -> new vertex on the + side
    for (Eigen::Vector3i& t : mesh.triangles) {
      if (Centroid(mesh, t)[axis] <= float(offset)) continue;
      for (int c = 0; c < 3; ++c) {
        auto it = moved.find(t[c]);
        if (it == moved.end()) {
          Eigen::Vector3f v = mesh.vertices[size_t(t[c])];
          v[axis] += float(options.seam_gap);
          mesh.vertices.push_back(v);
          it = moved.emplace(t[c], int(mesh.vertices.size()) - 1).first;
        }
        t[c] = it->second;
      }
    }
  }
  if (options.cluster_size > 0.0) {
    std::map<std::tuple<int, int, int>, int> cells;
    std::vector<Eigen::Vector3d> sum;
    std::vector<int> count, remap(mesh.vertices.size());
    for (size_t v = 0; v < mesh.vertices.size(); ++v) {
      const Eigen::Vector3d p = mesh.vertices[v].cast<double>() / options.cluster_size;
      const auto key = std::make_tuple(int(std::floor(p.x())), int(std::floor(p.y())), int(std::floor(p.z())));
      auto it = cells.find(key);
      if (it == cells.end()) {
        it = cells.emplace(key, int(sum.size())).first;
        sum.push_back(Eigen::Vector3d::Zero());
        count.push_back(0);
      }
      remap[v] = it->second;
      sum[size_t(it->second)] += mesh.vertices[v].cast<double>();
      ++count[size_t(it->second)];
    }
    Mesh decimated;
    for (size_t c = 0; c < sum.size(); ++c) decimated.vertices.push_back((sum[c] / count[c]).cast<float>());
    for (const Eigen::Vector3i& t : mesh.triangles) {
      const Eigen::Vector3i r(remap[size_t(t[0])], remap[size_t(t[1])], remap[size_t(t[2])]);
      if (r[0] != r[1] && r[1] != r[2] && r[0] != r[2]) decimated.triangles.push_back(r);
    }
    mesh = decimated;
  }
  if (options.delete_fraction > 0.0) {
    std::vector<Eigen::Vector3i> kept;
    for (const Eigen::Vector3i& t : mesh.triangles) {
      if (unit(rng) >= options.delete_fraction) kept.push_back(t);
    }
    mesh.triangles = kept;
  }
  for (Eigen::Vector3i& t : mesh.triangles) {
    if (unit(rng) < options.flip_fraction) std::swap(t[1], t[2]);
  }
  const size_t n = mesh.triangles.size();
  for (size_t t = 0; t < n; ++t) {
    if (unit(rng) < options.duplicate_fraction) {
      const Eigen::Vector3i f = mesh.triangles[t];
      mesh.triangles.emplace_back(f[0], f[2], f[1]);
    }
  }
  return mesh;
}

// The corpus' damage variants (one seed each).
inline std::vector<CrackOptions> CrackVariants() {
  std::vector<CrackOptions> variants;
  auto add = [&](CrackOptions o) { variants.push_back(o); };
  CrackOptions o;
  o = CrackOptions(); o.name = "delete 1 %"; o.delete_fraction = 0.01; o.seed = 11; add(o);
  o = CrackOptions(); o.name = "delete 5 %"; o.delete_fraction = 0.05; o.seed = 12; add(o);
  o = CrackOptions(); o.name = "3 seams, 4 cm gaps"; o.num_seams = 3; o.seam_gap = 0.04; o.seed = 13; add(o);
  o = CrackOptions(); o.name = "decimate (12 cm cells)"; o.cluster_size = 0.12; o.seed = 14; add(o);
  o = CrackOptions(); o.name = "flip 20 %, duplicate 10 %"; o.flip_fraction = 0.2; o.duplicate_fraction = 0.1;
  o.seed = 15; add(o);
  o = CrackOptions(); o.name = "3 interior boxes"; o.num_interior_boxes = 3; o.seed = 16; add(o);
  o = CrackOptions(); o.name = "all: 2 seams, decimate, delete 3 %, flip, boxes"; o.num_seams = 2;
  o.seam_gap = 0.03; o.cluster_size = 0.1; o.delete_fraction = 0.03; o.flip_fraction = 0.2;
  o.duplicate_fraction = 0.05; o.num_interior_boxes = 2; o.seed = 17; add(o);
  return variants;
}

// Clean car-like corpus meshes in the canonical frame (x front, y down, road
// y = 0): closed unions of ellipsoids standing on AddWheels' tyres.
inline Mesh MakeEllipsoidMesh(const Eigen::Vector3d& centre, const Eigen::Vector3d& half, int rings,
                              int segments) {
  Mesh mesh = MakeSphereMesh(Eigen::Vector3d::Zero(), 1.0, rings, segments);
  for (Eigen::Vector3f& v : mesh.vertices) {
    v = (v.cast<double>().cwiseProduct(half) + centre).cast<float>();
  }
  return mesh;
}

inline Mesh MakeSedanBody() {  // lower body + cabin, bottom at y = 0
  Mesh body = MakeEllipsoidMesh(Eigen::Vector3d(0, -0.45, 0), Eigen::Vector3d(2.1, 0.45, 0.85), 32, 64);
  body.Append(MakeEllipsoidMesh(Eigen::Vector3d(-0.3, -0.85, 0), Eigen::Vector3d(1.2, 0.45, 0.75), 24, 48));
  return body;
}

inline Mesh MakeVanBody() {  // tall rounded box-like body: a squashed high ellipsoid + bonnet
  Mesh body = MakeEllipsoidMesh(Eigen::Vector3d(-0.3, -0.9, 0), Eigen::Vector3d(1.9, 0.9, 0.9), 32, 64);
  body.Append(MakeEllipsoidMesh(Eigen::Vector3d(1.1, -0.45, 0), Eigen::Vector3d(1.0, 0.45, 0.85), 24, 48));
  return body;
}

// Wrong-sign voxels of `cracked` against `clean` on the same grid, counted
// over the voxels at least one voxel from the clean surface (|clean| >= h),
// and the clean inside among them.
struct SignDifference {
  int64_t wrong = 0;
  int64_t clean_inside = 0;
  double Share() const { return clean_inside > 0 ? double(wrong) / double(clean_inside) : 0.0; }
};

inline SignDifference CompareSigns(const GridSpec& grid, const std::vector<float>& clean,
                                   const std::vector<float>& cracked) {
  SignDifference d;
  const float h = float(grid.voxel_size);
  for (size_t v = 0; v < clean.size(); ++v) {
    if (std::abs(clean[v]) < h) continue;
    d.clean_inside += clean[v] < 0;
    d.wrong += (clean[v] < 0) != (cracked[v] < 0);
  }
  return d;
}

}  // namespace test
}  // namespace samp
