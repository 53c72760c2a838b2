// Training a shape manifold from a folder of CAD files: load, canonicalise,
// scan, SDF, PCA, model file (docs/training.md).
#pragma once

#include <string>
#include <vector>

#include "libsamp/core/grid_spec.h"
#include "libsamp/model/pca.h"
#include "libsamp/model/shape_model.h"
#include "libsamp/scan/canonical.h"
#include "libsamp/scan/scanner.h"
#include "libsamp/sdf/sdf.h"

namespace samp {

struct TrainOptions {
  std::string cad_folder;         // searched recursively for mesh files
  std::string manifest_path;      // optional JSON manifest ("" = none)
  // Optional canonicalisation preset ("shapenet", "apollocar3d"; "" = none)
  // for the files no manifest entry matches (CanonicalPreset, canonical.h).
  std::string preset;
  std::string output_path;        // the model .vdb
  std::string sdf_folder;         // optional: one <name>.vdb SDF per model ("" = none)
  GridSpec grid = GridSpec::CarDefault();
  ScanOptions scan;
  SdfOptions sdf;
  SdfQualityOptions gate;         // per-SDF quality gate (docs/training.md)
  PcaOptions pca;
  // Size augmentation (docs/training.md, "Size variants"): besides each usable
  // CAD car as it is, one copy per entry stretched by these factors of
  // (length, height, width) about the canonical origin (the bottom centre),
  // named "<name>@<l>x<h>x<w>". Five CAD cars span a narrow band of sizes;
  // real traffic has vans, SUVs and pickups. Empty (the default) = none.
  std::vector<Eigen::Vector3d> size_variants;
  int num_threads = 0;            // 0 = all cores
  bool show_progress = true;

  void Check() const;
  std::string ToJson() const;     // the effective options, stored in the model file
};

// The reader of TrainOptions::ToJson (the trainer options stored in a model
// file): every key ToJson writes is required; a missing key or a wrong type
// throws samp::Error naming `source` (e.g. the model file) and the key.
// show_progress and num_threads are not stored and keep their defaults.
// (Keep it in step with ToJson: the round-trip test in tests/model/trainer_test.cc
// fails when a field is written but not read.)
TrainOptions TrainOptionsFromJson(const std::string& json, const std::string& source);

struct TrainedShape {
  std::string name, file;
  bool used = false;
  std::string reject_reason;      // why it was skipped, when !used
  double scale = 1.0;
  Eigen::Vector3d size_factors = Eigen::Vector3d::Ones();  // a size variant's stretch (l, h, w)
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  // length, height, width after canonicalisation
  double inside_fraction = 0.0;
  SdfQuality quality;             // the gate's figures (when an SDF was computed)
  double seconds = 0.0;
};

struct TrainSummary {
  std::vector<TrainedShape> shapes;
  int num_used = 0;
  Eigen::VectorXd eigenvalues;
  double explained_variance = 0.0;  // share of the total variance in the kept R components
  double seconds = 0.0;
  std::string BriefReport() const;
};

// Throws samp::Error when fewer than R + 1 usable models remain (after reporting each rejection).
TrainSummary TrainShapeModel(const TrainOptions& options);

// The steps of TrainShapeModel one by one, for training elsewhere than in
// one process (the Python package's samp.batch train computes the SDFs on
// Dask workers and the PCA on the client; docs/cluster.md):
// ListTrainJobs lists the models as TrainShapeModel does (the CAD folder's
// mesh files in order, the manifest applied, then the size variants);
// TrainJobSdf computes one model's SDF as TrainShapeModel does (canonicalise,
// scan, SDF, quality gate, the sdf_folder file), filling `values` (D floats)
// when the model is usable; a rejection is in the returned shape's
// reject_reason, not thrown. Thread-safe for distinct `values`.
struct TrainJob {
  std::string path;           // as found
  std::string relative_path;  // relative to the CAD folder, '/'-separated
  std::string name;           // the training shape's name (unique)
  CanonicalizeOptions canonicalize;
  bool skip = false;          // skipped by the manifest
  std::string skip_reason;
  Eigen::Vector3d size_factors = Eigen::Vector3d::Ones();  // TrainOptions::size_variants
};
// Throws samp::Error when the CAD folder or the manifest cannot be read or holds no mesh.
std::vector<TrainJob> ListTrainJobs(const TrainOptions& options);
TrainedShape TrainJobSdf(const TrainJob& job, const TrainOptions& options, std::vector<float>* values);

// The chain from one CAD file to its SDF, written once for the trainer and
// `samp inspect --encode` (which encodes a CAD file as training would):
// CanonicalCad loads the mesh and puts it into the canonical frame, stretched
// by `size_factors` (length, height, width) about the bottom centre;
// ScanToSdf scans the canonical mesh and computes its SDF on `grid` (the
// caller checks Sdf::summary.sign_ok). Both throw samp::Error: on an
// unreadable or implausible mesh, or when no scan ray hits the mesh.
CanonicalizeResult CanonicalCad(const std::string& path, const CanonicalizeOptions& options,
                                const Eigen::Vector3d& size_factors = Eigen::Vector3d::Ones());
struct ScannedSdf {
  ScanResult scan;
  Sdf sdf;
};
ScannedSdf ScanToSdf(const Mesh& canonical_mesh, const ScanOptions& scan, const GridSpec& grid,
                     const SdfOptions& sdf);
// The same, scanning into *scan_result and reusing its buffers (ScanMesh's
// overload): TrainJobSdf leases one from a pool kept across models.
Sdf ScanToSdf(const Mesh& canonical_mesh, const ScanOptions& scan, const GridSpec& grid, const SdfOptions& sdf,
              ScanResult* scan_result);

}  // namespace samp
