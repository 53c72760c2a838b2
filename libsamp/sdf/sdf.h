// Signed distance fields of scanned CAD meshes on a metric voxel grid
// (docs/sdf.md). Distance: to the nearest point on the triangles that the
// scans hit (interior geometry no scan sees is ignored). Sign (docs/sdf.md,
// "Sign"): visibility carving (a voxel is outside if any scan view sees it in
// front of the surface or through empty space) combined with a closing of the
// surface: a voxel is inside when no view carves it, or when a flood fill from
// the grid's border through voxels farther than `closing_radius_voxels` from
// the surface cannot reach it (after undoing the offset). Cracks and holes
// narrower than about twice the closing radius then no longer let views carve
// cones into the interior; wide openings (open wheel arches, missing bottoms)
// let the fill in and leave the carving's sign as it was. Works on
// non-watertight meshes, soups and inconsistent winding.
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
  // How the sign is decided: kCarving alone (the sign before issue 14), or
  // kCarvingAndClosing (default): also inside where the closing says inside.
  enum class Sign { kCarving, kCarvingAndClosing };
  Sign sign = Sign::kCarvingAndClosing;
  // Closing radius tau in voxels (> 0): the flood fill passes only voxels
  // farther than tau voxels from the seen surface, so gaps narrower than
  // about 2 tau are closed.
  double closing_radius_voxels = 1.5;

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
  double closing_seconds = 0.0;    //   closing, combination and the quality figures (3)
  bool sign_ok = false;           // inside_fraction >= options.min_inside_fraction
  // Quality figures of the sign (the trainer's gate, docs/training.md):
  double carving_inside_fraction = 0.0;  // inside share of the grid by carving alone
  double closing_inside_fraction = 0.0;  // inside share by the closing alone (0: kCarving or no fill seed)
  // Voxels where carving and closing disagree, as a share of the final inside
  // voxels (0 when nothing is inside).
  double sign_disagreement = 0.0;
  // Share of the inside voxels in the largest 6-connected inside component.
  double largest_component_share = 0.0;
  int num_inside_components = 0;
  std::string BriefReport() const;
};

struct Sdf {
  GridSpec grid;
  std::vector<float> values;  // grid.NumVoxels() values, x-fastest, metres
  SdfSummary summary;
};

// The quality gate of one SDF (docs/training.md, "Quality gate"): figures
// that catch a sign that slipped through, with the limits that reject a
// model and the (stricter) ones that list it as borderline.
struct SdfQualityOptions {
  // Inside volume over the volume of the shape's bounding box (within the
  // grid): a car fills roughly half or more of its box.
  double min_box_fill = 0.30;
  double borderline_box_fill = 0.45;
  // Share of the inside voxels in the largest connected inside component.
  double min_largest_component = 0.95;
  double borderline_largest_component = 0.99;
  // Share of the inside voxels that the closing alone also calls inside: low
  // when the flood fill got in through a wide opening, so that the sign rests
  // on the carving alone (its cones included).
  double min_closing_agreement = 0.50;
  double borderline_closing_agreement = 0.90;

  void Check() const;  // throws samp::Error naming the field
};

struct SdfQuality {
  double box_fill = 0.0;
  double largest_component = 0.0;
  double closing_agreement = 0.0;
  bool pass = false;        // every figure at or above its minimum
  bool borderline = false;  // passes, but some figure is below its borderline limit
  // The figures that failed (or, when passing, are borderline), one phrase
  // each naming the figure, its value and the limit; empty when clean.
  std::string reason;
};

// Evaluates the gate for an SDF whose shape has the bounding box `shape_box`
// (object frame; clipped to the grid).
SdfQuality CheckSdfQuality(const Sdf& sdf, const AlignedBox& shape_box, const SdfQualityOptions& options);

// Computes the SDF of `mesh` (object frame) from its scans. Single-threaded per
// call unless `parallel` (TBB over z-slices). Its working buffers (about 60
// bytes per voxel plus the scan views' tables, ~60 KB per 400 x 400 view)
// are kept in a process-wide pool for the next call (core/object_pool.h):
// one set per call that ever ran at the same time, held until the process ends.
Sdf ComputeSdf(const Mesh& mesh, const ScanResult& scan, const GridSpec& grid,
               const SdfOptions& options, bool parallel = false);

}  // namespace samp
