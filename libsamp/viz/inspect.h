// Inspecting a shape manifold (`samp inspect`, docs/inspect.md): a text
// summary, the zero level sets of the mean and of eigen-shapes as mesh files,
// projecting new shapes (CAD models or per-model SDFs) into the manifold with
// reconstruction errors, and PNG pictures (a Figure-2-like sheet of training
// shapes, a grid of eigen-shapes).
// All functions take the model by const reference and are safe to call
// concurrently on the same model; outputs are written atomically.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "libsamp/core/camera.h"
#include "libsamp/core/mesh.h"
#include "libsamp/model/manifold_projection.h"
#include "libsamp/model/shape_model.h"
#include "libsamp/scan/canonical.h"
#include "libsamp/scan/scanner.h"
#include "libsamp/sdf/sdf.h"
#include "libsamp/viz/image.h"

namespace samp {

// ---- Summary ------------------------------------------------------------------

// Multi-line text: format version, grid (extent, voxel size, dimensions), R,
// eigenvalues with sigma, explained and cumulative variance (relative to the
// total variance when the file stores it, else to the kept R components, and
// the text says which), training shapes, the trainer's options. `path` is
// printed when not empty.
std::string SummarizeModel(const ShapeModel& model, const std::string& path = "");

// ---- Eigen-shape meshes -----------------------------------------------------------

struct EigenShapeMeshOptions {
  std::string output_folder;          // created if missing
  std::vector<double> ks = {-2.0, 0.0, 2.0};  // multiples of sigma_i (0 = the mean)
  std::string format = "ply";         // ply, obj or glb (assimp's exporter)
  int max_components = 0;             // components to export, 0 = all R

  void Check() const;
};

struct EigenShapeMeshSummary {
  std::vector<std::string> files;     // written, in order
  std::vector<std::string> empty;     // shapes whose zero level set is empty (not written)
  std::string BriefReport() const;
};

// Zero level sets of mu (file "mean.<format>") and of mu + k sigma_i w_i for
// every k != 0 and component i ("pc<i>_<+k>sd.<format>", e.g. pc1_-2.0sd.ply),
// in the object frame, metres.
EigenShapeMeshSummary WriteEigenShapeMeshes(const ShapeModel& model,
                                            const EigenShapeMeshOptions& options);

// ---- Encoding (projection into the manifold) ----------------------------------------

struct EncodeOptions {
  // A CAD file (any format LoadMesh reads), a per-model SDF .vdb (samp train
  // --sdf-dir), or a folder of them (searched recursively).
  std::string input;
  std::string output_folder;          // reconstructed meshes + encode.csv; "" = write nothing
  // CAD canonicalisation (scan/canonical.h); "" = CanonicalizeOptions defaults.
  std::string manifest_path;
  // Gaussian prior weight lambda: z = argmin |W z - (x - mu)|^2 + lambda sum z_i^2 / sigma_i^2,
  // i.e. z_i = w_i^T (x - mu) / (1 + lambda / sigma_i^2). 0 = plain least squares.
  double prior_weight = 0.0;
  // The RMS SDF error is taken over voxels with |sdf| < this many voxels.
  double near_surface_voxels = 2.0;
  std::string mesh_format = "ply";    // ply, obj or glb
  // Points sampled on each surface for the point-to-point distances.
  int num_distance_samples = 20000;
  uint64_t seed = 1;                  // sampling seed (logged in the table)

  void Check() const;
};

// Distances from each point of one set to its nearest point in another, metres.
struct DistanceStats {
  int64_t count = 0;
  double mean = 0.0, median = 0.0, p95 = 0.0, max = 0.0;
};

struct EncodedShape {
  std::string name, file;
  std::string kind;                   // "cad" or "sdf"
  bool ok = false;
  std::string error;                  // why it failed, when !ok
  Eigen::VectorXd code;               // z (R), metres of SDF norm along each w_i
  Eigen::VectorXd code_in_sigmas;     // z_i / sigma_i
  double rms_near_surface = 0.0;      // RMS of phi(z) - x over |x| < near_surface_voxels voxels
  int64_t num_near_voxels = 0;
  double rms_all = 0.0;               // RMS over the whole grid
  DistanceStats accuracy;             // reconstructed surface -> original surface
  DistanceStats completeness;         // original surface -> reconstructed surface
  std::string mesh_path;              // the reconstructed mesh, when written
};

struct EncodeSummary {
  std::vector<EncodedShape> shapes;
  double prior_weight = 0.0;
  std::string BriefReport() const;    // a table, one row per input
};

// Projects every input; a failing file is reported in its row, not thrown.
// Throws samp::Error on invalid options or when the input does not exist.
EncodeSummary EncodeShapes(const ShapeModel& model, const EncodeOptions& options);

// ---- Building blocks of encoding (used by the pictures and tests) -----------

// A shape to compare with the manifold: its SDF on the model grid and its
// original surface (the canonical CAD mesh, or the SDF's zero level set).
struct ShapeInput {
  std::string name, file, kind;       // kind: "cad" or "sdf"
  std::vector<float> sdf;             // model.grid.NumVoxels() values
  Mesh original;                      // object frame, metres
  // Points of the original surface for distances: the scanned (visible) CAD
  // surface, or vertices of the SDF's zero level set.
  std::vector<Eigen::Vector3f> original_points;
  std::string source_file;            // an SDF file's "samp_source_file" metadata, if any
};

// Loads a CAD file (load + canonicalise with the manifest entry or defaults +
// scan + SDF on the model grid, with the scan/SDF options the model was
// trained with, from its options_json) or a per-model SDF .vdb (must lie on
// the model grid). Throws samp::Error naming the file.
ShapeInput LoadShapeInput(const std::string& path, const ShapeModel& model,
                          const std::string& manifest_path = "");

// ProjectToManifold (z = W^T (x - mu) with the optional prior, see
// EncodeOptions::prior_weight) is model/manifold_projection.h.

// `count` points sampled uniformly by area on the triangles (seeded).
std::vector<Eigen::Vector3f> SampleSurface(const Mesh& mesh, int count, uint64_t seed);
// For every point of `from`, the distance to the nearest point of `to`.
DistanceStats NearestDistances(const std::vector<Eigen::Vector3f>& from,
                               const std::vector<Eigen::Vector3f>& to);
// The same distances one by one (inf for every point when `to` is empty).
std::vector<double> NearestDistanceEach(const std::vector<Eigen::Vector3f>& from,
                                        const std::vector<Eigen::Vector3f>& to);

// ---- Pictures -------------------------------------------------------------------

// A camera looking at the centre of `bounds` from a three-quarter view
// (object frame: x front, y down, z left), framing the box tightly.
struct ViewOptions {
  int width = 640, height = 360;      // pixels
  double azimuth_deg = 40.0;          // from the front (+x) towards the left side (+z)
  double elevation_deg = 22.0;        // above the horizon
  double margin = 0.04;               // free border, share of the image size
};
struct View {
  PinholeCamera camera;
  Eigen::Isometry3d camera_from_object = Eigen::Isometry3d::Identity();
};
View ThreeQuarterView(const AlignedBox& bounds, const ViewOptions& options);

// Renders meshes (object frame) with the project's renderer and simple shading,
// anti-aliased by 2x2 supersampling; `colors` RGB in [0, 1], one per mesh.
RgbImage RenderMeshes(const std::vector<const Mesh*>& meshes,
                      const std::vector<Eigen::Vector3f>& colors, const View& view);

struct PictureOptions {
  std::string output_folder;          // eigen_shapes.png and shapes.png go here
  // Shapes for the sheet: per-model SDFs written by `samp train --sdf-dir`, or
  // CAD files (+ manifest) as for encoding. Neither: no sheet is drawn.
  std::string sdf_folder;
  std::string cad_folder;
  std::string manifest_path;
  int num_sheet_shapes = 4;           // training shapes on the sheet (the first ones found)
  std::vector<double> sigmas = {-2.0, -1.0, 0.0, 1.0, 2.0};  // eigen-shape grid columns
  int max_components = 0;             // eigen-shape grid rows, 0 = all R
  int cell_width = 300;               // one picture cell, pixels
  int cell_height = 170;

  void Check() const;
};

// The eigen-shape grid: rows = components, columns = mu + k sigma_i w_i for k in `sigmas`.
RgbImage RenderEigenShapeGrid(const ShapeModel& model, const PictureOptions& options);
// The sheet: per shape a row with the original rendered, an SDF slice (z = 0,
// coloured by sign, zero level drawn), the manifold's reconstruction rendered
// and a bar plot of its code in units of sigma.
RgbImage RenderShapeSheet(const ShapeModel& model, const std::vector<ShapeInput>& shapes,
                          const PictureOptions& options);
// An SDF slice at the grid index nearest to z = 0 (object frame), coloured by
// sign (blue inside, red outside, white at 0) with the zero level in black,
// `scale` output pixels per voxel.
RgbImage RenderSdfSlice(const GridSpec& grid, const std::vector<float>& sdf, int scale);

struct PictureSummary {
  std::vector<std::string> files;
  std::string BriefReport() const;
};
// Writes eigen_shapes.png and, when shapes are available, shapes.png.
PictureSummary WritePictures(const ShapeModel& model, const PictureOptions& options);

}  // namespace samp
