// The stages of ComputeSdf (sdf.cc, docs/sdf.md), each in its own file:
// the unsigned distance to the seen triangles (sdf_distance.cc), the sign by
// visibility carving (sdf_carving.cc) and by the closing of the surface
// (sdf_closing.cc). Internal to libsamp/sdf: not installed, not part of the
// interface. Every function here is thread-safe for distinct outputs (the
// slab functions for disjoint slabs of one output).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "libsamp/core/grid_spec.h"
#include "libsamp/scan/scanner.h"
#include "libsamp/sdf/sdf.h"

namespace samp {
namespace sdf_internal {

using Vec3 = Eigen::Vector3f;

// A seen triangle, with its unit normal and plane offset (n . x = offset).
struct Triangle {
  Vec3 a, b, c;
  Vec3 normal;
  float offset;
};

// ---- Distance (sdf_distance.cc) ----

// Far-away "closest point" of voxels not reached yet: its squared distance
// (~3e30) loses every comparison and stays finite in float.
constexpr float kFar = 1e15f;

// Squared distance and closest surface point (x, y, z) per voxel.
struct DistanceField {
  std::vector<float> squared;
  std::vector<float> x, y, z;
};

// Exact distances for the voxels with k in [k_begin, k_end) within `band` of
// the triangles in `triangles` (indices into `all`).
void SeedBand(const GridSpec& grid, const std::vector<Triangle>& all,
              const std::vector<int32_t>& triangles, float band, int k_begin, int k_end,
              DistanceField* field);

// The closest points of the band propagated to the whole grid (two forward
// and two backward raster passes, serial: each pass depends on the previous
// voxels), then the distances (*distance resized to the grid).
void PropagateDistances(const GridSpec& grid, DistanceField* field, std::vector<float>* distance);

// ---- Carving (sdf_carving.cc) ----

// One scan view as the carving uses it (object frame, float).
struct CarveView {
  Eigen::Matrix3f rotation;     // camera_from_object
  Vec3 translation;
  Vec3 camera_center;           // in the object frame
  float fx, fy, cx, cy;
  int width, height;
  float lateral_per_depth;      // half pixel diagonal per metre of depth (+10 %)
  const float* depth;
  const int32_t* triangle;
  // Every kCoarseStep-th pixel (from kCoarseOffset) along both axes: a small
  // image that stays in cache, used for voxels far enough from the surface.
  int coarse_width = 0, coarse_height = 0;
  std::vector<float> coarse_depth;
  // Minimum and maximum depth (inf included) over cells of kCell x kCell
  // pixels: a block of voxels whose pixels lie in a few cells is decided at once.
  int cell_width = 0, cell_height = 0;
  std::vector<float> cell_min, cell_max;
};

// The views of the scan, with their tables, in *views (its tables' buffers
// reused); they point into `scan`'s images, so `scan` must outlive them.
// Throws samp::Error for a view whose depth or triangle image does not match
// its camera.
void MakeCarveViews(const ScanResult& scan, std::vector<CarveView>* views);

// Voxels within this distance of the surface may be "near" (docs/sdf.md) for
// some view: the largest lateral_per_depth times the largest camera depth
// of a grid corner (an upper bound of every voxel's depth).
float NearDistance(const GridSpec& grid, const std::vector<CarveView>& views);

// A voxel not carved yet.
struct Active {
  Vec3 position;
  float distance;
  int32_t index;
  uint8_t in_frustum;  // some view had it in its image
  uint8_t cell;        // its 2^3 cell within its block (voxels of a cell are contiguous)
};

// A set of voxels (a block, a cell, or the near voxels of a block): a
// segment [begin, begin + count) of the active list.
struct Block {
  int begin = 0, count = 0;
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  // bounding box of the active voxel centres
  Vec3 centre = Vec3::Zero();  // of the box, and the radius of a sphere around it (Bound)
  float radius = 0.f;
  float min_distance = 0.f;  // smallest distance of the active voxels
  bool seen = false;         // some view had all of them in its image
  bool per_voxel = false;    // voxels near the surface: always tested one by one
  bool stale = true;         // (cells) lo, hi, min_distance to be recomputed
};

// The voxels of a slab not carved yet: blocks of kBlock^3 voxels in raster
// order, their voxels ordered by cell; the voxels of each block that may be
// near the surface for some view form a block of their own, tested voxel by
// voxel.
struct SlabVoxels {
  std::vector<Active> active;
  std::vector<Block> blocks;
  std::vector<Block> cells;  // 8 per block (the 2^3 cells of block b at 8 * b)
  std::vector<Active> near;  // scratch: the near voxels of one block
};

// Carves the voxels with k in [k_begin, k_end): sets outside[v] = 1 for the
// voxels some view sees in front of the surface, or that no view sees.
// *slab holds the working set (its buffers reused).
void CarveSlab(const GridSpec& grid, const std::vector<CarveView>& views,
               const std::vector<Triangle>& triangles, const std::vector<int32_t>& triangle_index,
               const std::vector<float>& distance, float near_distance, const SdfOptions& options,
               int k_begin, int k_end, SlabVoxels* slab, std::vector<uint8_t>* outside);

// ---- Closing (sdf_closing.cc) ----

// The working set of a flood fill over the grid: a mark per voxel and the
// voxels to visit (buffers reused between calls).
struct FloodBuffers {
  std::vector<uint8_t> mark;
  std::vector<int32_t> queue;
};

// The closing of the seen surface with radius tau = radius_voxels * h
// (docs/sdf.md, "Sign"): O = the voxels farther than tau from the surface
// that a 6-connected flood fill reaches from the grid's border, starting at
// border voxels that the carving also calls outside (a body cut by the grid
// border does not seed the fill). A voxel in O is outside. So is every voxel
// in the open ball of radius d(o) around some o in O: that ball holds no
// surface, so it lies wholly on o's side (exact up to the grid). Voxels
// within tau of the surface look for such a ball among the O voxels within
// tau + 1.5 h; voxels on the surface (d <= 1e-3 h, no direction) keep the
// carving's word. Every other voxel is inside: gaps narrower than about 2 tau
// are closed, and concave corners keep their shape (they are covered by the
// balls of the O voxels beyond them). Returns false, leaving *closed_outside
// empty, when no border voxel can seed the fill.
bool ClosingOutside(const GridSpec& grid, const std::vector<float>& distance,
                    const std::vector<uint8_t>& carved, float radius_voxels,
                    FloodBuffers* buffers, std::vector<uint8_t>* closed_outside);

// Number of 6-connected components of the inside voxels (outside[v] == 0)
// and the share of the inside voxels in the largest one (0 when none).
void InsideComponents(const GridSpec& grid, const std::vector<uint8_t>& outside, FloodBuffers* buffers,
                      int* num_components, double* largest_share);

}  // namespace sdf_internal
}  // namespace samp
