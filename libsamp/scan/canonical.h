// Bringing CAD models into samp's canonical object frame (docs/canonical_frame.md):
// metric, KITTI object frame: origin at the centre of the bottom face of the
// bounding box, x along the length pointing to the front, y down, z along the
// width pointing to the car's left (right-handed: z = x cross y).
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "libsamp/core/mesh.h"
#include "libsamp/core/wheels.h"

namespace samp {

// How one CAD file maps to the canonical frame. Axes are "+x", "-x", "+y",
// "-y", "+z", "-z" in the CAD file's own coordinates, or "auto".
struct CanonicalizeOptions {
  // Multiplies CAD units to metres. Exclusive with target_length.
  std::optional<double> scale;
  // Scales so that the car's length (extent along `forward`) is this many metres.
  std::optional<double> target_length;
  // The CAD axis pointing up (towards the sky). "auto": the smallest extent among
  // the two axes that are not the length... see Canonicalize().
  std::string up = "auto";
  // The CAD axis pointing to the front of the car. "auto": the longest horizontal extent;
  // the sign cannot be told from the bounding box and is kept positive (a warning says so).
  std::string forward = "auto";
  // Plausible canonical size range for a car, metres (length, height, width).
  Eigen::Vector3d min_size = Eigen::Vector3d(2.5, 0.9, 1.2);
  Eigen::Vector3d max_size = Eigen::Vector3d(7.0, 2.8, 2.8);
  // Bodies without wheels (TORCS, Trigger Rally): lift the body and add four
  // tyres touching y = 0 (AddWheels, libsamp/core/wheels.h). Manifest key
  // "wheels": "synthesise" (true) or "mesh" (false: the mesh has its own, or
  // none are wanted).
  bool add_wheels = false;
  WheelOptions wheels;

  void Check() const;
};

// Canonicalisation presets of public CAD datasets (docs/canonical_frame.md):
//   "shapenet"     ShapeNetCore v2 model_normalized.obj: +y up, front -z, unit
//                  bounding-box diagonal -> scale 4.49 (KITTI's mean car,
//                  3.90 x 1.56 x 1.60 m, has a 4.49 m diagonal); own wheels.
//   "apollocar3d"  ApolloCar3D car_models_json (ReadApolloCarJson): metres,
//                  y down (up -y), front +z; own wheels.
// Throws samp::Error naming the known presets for an unknown name.
CanonicalizeOptions CanonicalPreset(const std::string& name);
std::vector<std::string> CanonicalPresetNames();

struct CanonicalizeResult {
  Mesh mesh;                         // in the canonical frame, metres
  Eigen::Affine3d object_from_cad;   // the applied transform (rotation * scale + translation)
  double scale = 1.0;                // CAD units -> metres
  std::string up, forward;           // the axes used (after auto-detection)
  Eigen::Vector3d size;              // length (x), height (y), width (z) in metres
  std::vector<std::string> warnings; // ambiguities met by auto-detection
  // With options.add_wheels: where the tyres went (mesh = lifted body + tyres;
  // object_from_cad includes the lift; size is that of the body + tyres).
  bool wheels_added = false;
  WheelPlacement wheels;
};

// Throws samp::Error when the mesh is empty or the size after scaling is implausible.
CanonicalizeResult Canonicalize(const Mesh& cad_mesh, const CanonicalizeOptions& options);

// One entry of a training manifest (JSON, documented in docs/canonical_frame.md).
struct ManifestEntry {
  std::string file;  // path relative to the manifest's folder (or the CAD folder)
  std::string name;  // shape name; default: file stem
  CanonicalizeOptions canonicalize;
  bool skip = false;
  std::string skip_reason;
};

struct Manifest {
  // Defaults applied to files that the manifest does not list.
  CanonicalizeOptions defaults;
  std::vector<ManifestEntry> entries;
  // The entry for a file (matched by relative path or file name), or nullptr.
  const ManifestEntry* Find(const std::string& relative_path) const;
};

// Parses a manifest; throws samp::Error naming the file and the field.
Manifest LoadManifest(const std::string& path);

// One mesh file of a CAD folder and what the manifest says of it.
struct CadFile {
  std::string path;                      // as found below the folder
  std::string relative_path;             // relative to the CAD folder, '/'-separated
  const ManifestEntry* entry = nullptr;  // its manifest entry (Manifest::Find), or nullptr
  std::string name;                      // the entry's name, else the file stem
  CanonicalizeOptions canonicalize;      // the entry's options, else the manifest's defaults
};

// The CAD folder walk of `samp train` and `samp synth --cad`: the mesh files
// below `folder` (ListMeshFiles: symlinked folders followed, each folder
// once), sorted by relative path, each matched to `manifest` (nullptr: none;
// else it must outlive the result, whose entries point into it). Throws
// samp::Error naming the folder when it cannot be listed.
std::vector<CadFile> ListCadFiles(const std::string& folder, const Manifest* manifest);

}  // namespace samp
