// Signed distance fields from scans (docs/sdf.md).
//
// 1. Unsigned distance to the triangles the scans saw (sdf_distance.cc):
//    a. exact narrow band: every seen triangle visits the voxels of its
//       bounding box grown by one voxel, rejects those whose distance to its
//       plane exceeds the band radius, and computes the exact closest point on
//       the triangle for the rest (keeping the nearest per voxel);
//    b. the rest of the grid by vector (closest-point) propagation: a forward
//       and a backward raster pass, each offering every voxel the closest
//       points of its 13 already-visited neighbours (Danielsson/Ragnemalm).
// 2. Sign by visibility carving (sdf_carving.cc): a voxel is outside if some
//    view sees it in front of the observed surface (or through empty space);
//    near the surface the pixel-centre depth is replaced by the plane of the
//    triangle the pixel saw, so the zero crossing does not depend on the pixel
//    grid.
// 3. Closing of the surface (sdf_closing.cc): inside where either the carving
//    or the closing says inside.
// This file: the options, the quality gate, and ComputeSdf, which runs the
// stages (sdf_stages.h) slab by slab where they allow it.
#include "libsamp/sdf/sdf.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <cstdio>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/core/object_pool.h"
#include "libsamp/sdf/sdf_option_table.h"
#include "libsamp/sdf/sdf_stages.h"

namespace samp {

void SdfOptions::Check() const { SdfOptionTable().Check(*this); }

void SdfQualityOptions::Check() const { SdfQualityOptionTable().Check(*this); }

SdfQuality CheckSdfQuality(const Sdf& sdf, const AlignedBox& shape_box, const SdfQualityOptions& options) {
  options.Check();
  SdfQuality q;
  const GridSpec& grid = sdf.grid;
  // The shape's box within the grid's box (voxel centres +- h / 2).
  const Eigen::Vector3d half(0.5 * grid.voxel_size, 0.5 * grid.voxel_size, 0.5 * grid.voxel_size);
  const Eigen::Vector3d lo = shape_box.min.cwiseMax(grid.MinCorner() - half);
  const Eigen::Vector3d hi = shape_box.max.cwiseMin(grid.MaxCorner() + half);
  const double box_volume = (hi - lo).cwiseMax(0.0).prod();
  const double inside_volume =
      sdf.summary.inside_fraction * double(grid.NumVoxels()) * std::pow(grid.voxel_size, 3);
  q.box_fill = box_volume > 0.0 ? inside_volume / box_volume : 0.0;
  q.largest_component = sdf.summary.largest_component_share;
  q.closing_agreement = sdf.summary.inside_fraction > 0.0
                            ? std::min(1.0, sdf.summary.closing_inside_fraction / sdf.summary.inside_fraction)
                            : 0.0;
  std::ostringstream failed, borderline;
  auto check = [&](const char* name, double value, double minimum, double limit) {
    char text[160];
    if (value < minimum) {
      std::snprintf(text, sizeof(text), "%s%s %.3f below the minimum %.3f", failed.tellp() > 0 ? "; " : "", name,
                    value, minimum);
      failed << text;
    } else if (value < limit) {
      std::snprintf(text, sizeof(text), "%s%s %.3f below %.3f", borderline.tellp() > 0 ? "; " : "", name, value,
                    limit);
      borderline << text;
    }
  };
  check("inside volume / box volume", q.box_fill, options.min_box_fill, options.borderline_box_fill);
  check("largest inside component share", q.largest_component, options.min_largest_component,
        options.borderline_largest_component);
  check("closing agreement", q.closing_agreement, options.min_closing_agreement,
        options.borderline_closing_agreement);
  q.pass = failed.tellp() == 0;
  q.borderline = q.pass && borderline.tellp() > 0;
  q.reason = q.pass ? borderline.str() : failed.str();
  return q;
}

std::string SdfSummary::BriefReport() const {
  std::ostringstream s;
  s << "SDF: " << num_seen_triangles << " seen triangles, inside fraction "
    << inside_fraction << (sign_ok ? "" : " (too small: sign failed)")
    << " (carving " << carving_inside_fraction << ", closing " << closing_inside_fraction
    << ", disagreement " << sign_disagreement << "), largest inside component "
    << largest_component_share << " of " << num_inside_components << ", " << seconds << " s";
  return s.str();
}

namespace {

using sdf_internal::CarveSlab;
using sdf_internal::CarveView;
using sdf_internal::ClosingOutside;
using sdf_internal::DistanceField;
using sdf_internal::FloodBuffers;
using sdf_internal::InsideComponents;
using sdf_internal::kFar;
using sdf_internal::MakeCarveViews;
using sdf_internal::NearDistance;
using sdf_internal::PropagateDistances;
using sdf_internal::SeedBand;
using sdf_internal::SlabVoxels;
using sdf_internal::Triangle;
using sdf_internal::Vec3;

// Throws samp::Error for input ComputeSdf cannot use, naming it.
void CheckSdfInput(const Mesh& mesh, const ScanResult& scan, const GridSpec& grid, const SdfOptions& options) {
  options.Check();
  grid.Check();
  SAMP_CHECK(grid.NumVoxels() < std::numeric_limits<int32_t>::max())
      << "ComputeSdf: the grid has too many voxels (" << grid.NumVoxels() << ")";
  SAMP_CHECK(scan.triangle_seen.size() == mesh.triangles.size())
      << "ComputeSdf: the scan has " << scan.triangle_seen.size()
      << " triangle flags, the mesh has " << mesh.triangles.size() << " triangles";
}

// The buffers of one ComputeSdf call, kept for the next (a pool below,
// core/object_pool.h): on the benchmark's grid they are ~25 MB, whose fresh
// pages cost a quarter of the call (docs/benchmarks.md, "SDF").
struct SdfWorkspace {
  std::vector<int32_t> triangle_index;
  std::vector<Triangle> triangles;
  std::vector<std::vector<int32_t>> slab_triangles;
  DistanceField field;
  std::vector<float> distance;
  std::vector<CarveView> views;
  std::vector<SlabVoxels> slabs;
  std::vector<uint8_t> outside, closed_outside;
  FloodBuffers flood;
};

ObjectPool<SdfWorkspace>& SharedWorkspaces() {
  static ObjectPool<SdfWorkspace> pool;
  return pool;
}

// The triangles the scans saw, with their planes, in *triangles;
// *triangle_index maps mesh triangle -> seen index or -1. Throws samp::Error
// for a vertex index out of range or when no triangle was seen.
void SeenTriangles(const Mesh& mesh, const ScanResult& scan, std::vector<int32_t>* triangle_index,
                   std::vector<Triangle>* triangles_out) {
  std::vector<Triangle>& triangles = *triangles_out;
  triangles.clear();
  triangles.reserve(size_t(std::count(scan.triangle_seen.begin(), scan.triangle_seen.end(), uint8_t(1))) +
                    1);
  triangle_index->assign(mesh.triangles.size(), -1);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (!scan.triangle_seen[t]) continue;
    const Eigen::Vector3i& f = mesh.triangles[t];
    for (int c = 0; c < 3; ++c) {
      SAMP_CHECK(f[c] >= 0 && size_t(f[c]) < mesh.vertices.size())
          << "ComputeSdf: triangle " << t << " has vertex index " << f[c] << " out of range";
    }
    Triangle tri;
    tri.a = mesh.vertices[size_t(f[0])];
    tri.b = mesh.vertices[size_t(f[1])];
    tri.c = mesh.vertices[size_t(f[2])];
    const Eigen::Vector3d n = (tri.b - tri.a).cast<double>().cross((tri.c - tri.a).cast<double>());
    const double norm = n.norm();
    tri.normal = norm > 0 ? Vec3((n / norm).cast<float>()) : Vec3::Zero();
    tri.offset = tri.normal.dot(tri.a);
    (*triangle_index)[t] = int32_t(triangles.size());
    triangles.push_back(tri);
  }
  SAMP_CHECK(!triangles.empty()) << "ComputeSdf: the scans saw no triangle of the mesh";
}

// Slabs of z-slices, the unit of parallel work: `size` slices each (8 when
// parallel, else one slab of the whole grid).
struct Slabs {
  int nz = 0;
  bool parallel = false;
  int size = 0;
  int count = 0;

  // Calls body(k_begin, k_end) for every slab, in parallel (TBB) when parallel.
  template <typename Body>
  void ForEach(const Body& body) const {
    if (parallel) {
      tbb::parallel_for(tbb::blocked_range<int>(0, count, 1), [&](const tbb::blocked_range<int>& r) {
        for (int s = r.begin(); s < r.end(); ++s) body(s * size, std::min(nz, (s + 1) * size));
      });
    } else {
      body(0, nz);
    }
  }
};

Slabs MakeSlabs(int nz, bool parallel) {
  Slabs slabs;
  slabs.nz = nz;
  slabs.parallel = parallel;
  slabs.size = parallel ? 8 : nz;
  slabs.count = (nz + slabs.size - 1) / slabs.size;
  return slabs;
}

// Seconds since the previous call (the first: since `start`).
class LapTimer {
 public:
  explicit LapTimer(std::chrono::steady_clock::time_point start) : last_(start) {}
  double operator()() {
    const auto now = std::chrono::steady_clock::now();
    const double seconds = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return seconds;
  }

 private:
  std::chrono::steady_clock::time_point last_;
};

// The seen triangles (indices into `triangles`) within `band` of the slices
// of each slab, in *slab_triangles (its buffers reused).
void TrianglesOfSlabs(const GridSpec& grid, const std::vector<Triangle>& triangles, float band, const Slabs& slabs,
                      std::vector<std::vector<int32_t>>* slab_triangles_out) {
  const int nz = grid.dims.z();
  std::vector<std::vector<int32_t>>& slab_triangles = *slab_triangles_out;
  slab_triangles.resize(static_cast<size_t>(slabs.count));
  for (std::vector<int32_t>& list : slab_triangles) list.clear();
  const float inv_h = float(1.0 / grid.voxel_size);
  const float oz = float(grid.origin.z());
  const float band_voxels = band * inv_h;
  for (size_t t = 0; t < triangles.size(); ++t) {
    const Triangle& tri = triangles[t];
    const float zmin = std::min({tri.a.z(), tri.b.z(), tri.c.z()});
    const float zmax = std::max({tri.a.z(), tri.b.z(), tri.c.z()});
    const int k0 = std::max(0, int(std::ceil((zmin - oz) * inv_h - band_voxels)));
    const int k1 = std::min(nz - 1, int(std::floor((zmax - oz) * inv_h + band_voxels)));
    if (k0 > k1) continue;
    for (int s = k0 / slabs.size; s <= k1 / slabs.size; ++s) slab_triangles[size_t(s)].push_back(int32_t(t));
  }
}

// 1a. Exact narrow band (one voxel): the exact distance and closest point
// of every voxel within a voxel of the seen triangles; kFar elsewhere
// (workspace->field).
void NarrowBand(const GridSpec& grid, const Slabs& slabs, SdfWorkspace* workspace) {
  const size_t num_voxels = size_t(grid.NumVoxels());
  const float band = float(grid.voxel_size);
  DistanceField& field = workspace->field;
  field.squared.assign(num_voxels, std::numeric_limits<float>::infinity());
  field.x.assign(num_voxels, kFar);
  field.y.assign(num_voxels, kFar);
  field.z.assign(num_voxels, kFar);
  const std::vector<Triangle>& triangles = workspace->triangles;
  TrianglesOfSlabs(grid, triangles, band, slabs, &workspace->slab_triangles);
  const std::vector<std::vector<int32_t>>& slab_triangles = workspace->slab_triangles;
  slabs.ForEach([&](int k_begin, int k_end) {
    SeedBand(grid, triangles, slab_triangles[size_t(k_begin / slabs.size)], band, k_begin, k_end, &field);
  });
}

// 2. Sign by visibility carving: workspace->outside[v] = 1 for the voxels
// some view sees in front of the surface, or that no view sees.
void CarveOutside(const GridSpec& grid, const ScanResult& scan, const SdfOptions& options, const Slabs& slabs,
                  SdfWorkspace* workspace) {
  MakeCarveViews(scan, &workspace->views);
  const float near_distance = NearDistance(grid, workspace->views);
  workspace->outside.assign(size_t(grid.NumVoxels()), 0);
  workspace->slabs.resize(size_t(slabs.count));
  slabs.ForEach([&](int k_begin, int k_end) {
    CarveSlab(grid, workspace->views, workspace->triangles, workspace->triangle_index, workspace->distance,
              near_distance, options, k_begin, k_end, &workspace->slabs[size_t(k_begin / slabs.size)],
              &workspace->outside);
  });
}

// 3. Closing, and the sign: inside where either says inside (*outside
// updated). Sets the carving's and the closing's inside fractions in
// *summary; returns the number of voxels where the two disagree.
int64_t CloseOutside(const GridSpec& grid, const SdfOptions& options, SdfWorkspace* workspace,
                     SdfSummary* summary) {
  const std::vector<float>& distance = workspace->distance;
  std::vector<uint8_t>& outside = workspace->outside;
  const size_t num_voxels = outside.size();
  int64_t carving_inside = 0;
  for (size_t v = 0; v < num_voxels; ++v) carving_inside += int64_t(!outside[v]);
  std::vector<uint8_t>& closed_outside = workspace->closed_outside;
  // kCarving: the sign before issue 14, no closing (closing_inside_fraction stays 0).
  const bool closing = options.sign == SdfOptions::Sign::kCarvingAndClosing &&
                       ClosingOutside(grid, distance, outside, float(options.closing_radius_voxels),
                                      &workspace->flood, &closed_outside);
  int64_t closing_inside = 0, disagree = 0;
  if (closing) {
    for (size_t v = 0; v < num_voxels; ++v) {
      closing_inside += int64_t(!closed_outside[v]);
      disagree += int64_t(closed_outside[v] != outside[v]);
    }
    for (size_t v = 0; v < num_voxels; ++v) outside[v] &= closed_outside[v];
  }
  summary->carving_inside_fraction = double(carving_inside) / double(num_voxels);
  summary->closing_inside_fraction = double(closing_inside) / double(num_voxels);
  return disagree;
}

// The signed distances (negative inside), clamped to +-truncation when
// truncation > 0; returns the number of inside voxels.
int64_t SignedValues(const std::vector<float>& distance, const std::vector<uint8_t>& outside, float truncation,
                     std::vector<float>* values) {
  const size_t num_voxels = distance.size();
  values->resize(num_voxels);
  int64_t inside = 0;
  for (size_t v = 0; v < num_voxels; ++v) {
    float value = outside[v] ? distance[v] : -distance[v];
    if (!outside[v]) ++inside;
    if (truncation > 0.0f) value = std::clamp(value, -truncation, truncation);
    (*values)[v] = value;
  }
  return inside;
}

}  // namespace

Sdf ComputeSdf(const Mesh& mesh, const ScanResult& scan, const GridSpec& grid,
               const SdfOptions& options, bool parallel) {
  const auto start = std::chrono::steady_clock::now();
  CheckSdfInput(mesh, scan, grid, options);
  const ObjectPool<SdfWorkspace>::Lease workspace(&SharedWorkspaces());
  SeenTriangles(mesh, scan, &workspace->triangle_index, &workspace->triangles);
  const size_t num_voxels = size_t(grid.NumVoxels());
  const Slabs slabs = MakeSlabs(grid.dims.z(), parallel);
  LapTimer lap(start);
  Sdf sdf;
  sdf.summary.setup_seconds = lap();

  NarrowBand(grid, slabs, workspace.get());
  sdf.summary.band_seconds = lap();
  PropagateDistances(grid, &workspace->field, &workspace->distance);
  sdf.summary.propagation_seconds = lap();

  CarveOutside(grid, scan, options, slabs, workspace.get());
  sdf.summary.carving_seconds = lap();

  const int64_t disagree = CloseOutside(grid, options, workspace.get(), &sdf.summary);
  sdf.grid = grid;
  const std::vector<uint8_t>& outside = workspace->outside;
  const int64_t inside = SignedValues(workspace->distance, outside, float(options.truncation), &sdf.values);
  sdf.summary.sign_disagreement = inside > 0 ? double(disagree) / double(inside) : 0.0;
  InsideComponents(grid, outside, &workspace->flood, &sdf.summary.num_inside_components,
                   &sdf.summary.largest_component_share);
  sdf.summary.closing_seconds = lap();
  sdf.summary.num_seen_triangles = int(workspace->triangles.size());
  sdf.summary.inside_fraction = double(inside) / double(num_voxels);
  sdf.summary.sign_ok = sdf.summary.inside_fraction >= options.min_inside_fraction;
  sdf.summary.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return sdf;
}

}  // namespace samp
