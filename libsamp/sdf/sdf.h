// Signed distance fields of scanned CAD meshes on a metric voxel grid
// (docs/sdf.md). Distance: to the nearest point on the triangles that the
// scans hit (interior geometry no scan sees is ignored). Sign by visibility
// carving: a voxel is outside (positive) if any scan view sees it in front of
// the surface or through empty space, inside (negative) otherwise. Works on
// non-watertight meshes.
#pragma once

#include <vector>

#include "libsamp/core/grid_spec.h"
#include "libsamp/core/mesh.h"
#include "libsamp/scan/scanner.h"

namespace samp {

struct SdfOptions {
  // Distances are clamped to +-truncation metres (0 = no clamping).
  double truncation = 0.0;
  // A voxel seen in front of the observed surface by less than this margin
  // (metres) is not carved: it absorbs depth discretisation near the surface.
  double carve_margin = 0.0;
  // A model is rejected when the inside fraction of the grid is below this.
  double min_inside_fraction = 0.01;

  void Check() const;
};

struct SdfSummary {
  double inside_fraction = 0.0;   // share of voxels with negative value
  int num_seen_triangles = 0;     // triangles the distance is measured to
  double seconds = 0.0;            // wall-clock time of ComputeSdf, of which:
  double setup_seconds = 0.0;      //   checks, seen triangles
  double band_seconds = 0.0;       //   exact narrow band (1a)
  double propagation_seconds = 0.0;  // closest-point propagation (1b)
  double carving_seconds = 0.0;    //   visibility carving incl. per-view tables (2)
  bool sign_ok = false;           // inside_fraction >= options.min_inside_fraction
  std::string BriefReport() const;
};

struct Sdf {
  GridSpec grid;
  std::vector<float> values;  // grid.NumVoxels() values, x-fastest, metres
  SdfSummary summary;
};

// Computes the SDF of `mesh` (object frame) from its scans. Single-threaded per
// call unless `parallel` (TBB over z-slices).
Sdf ComputeSdf(const Mesh& mesh, const ScanResult& scan, const GridSpec& grid,
               const SdfOptions& options, bool parallel = false);

}  // namespace samp
