// Dense grids <-> OpenVDB FloatGrids, and .vdb files (written atomically).
// Only this layer and model/ include OpenVDB headers.
//
// Files written by WriteVdb carry their size and a checksum of all their bytes
// in the file metadata. OpenVDB writes the files; ReadVdb never hands a byte
// to OpenVDB's reader (which is not safe on corrupt input): it parses the
// header, the file metadata and the grid descriptors itself with bounds
// checks, verifies size and checksum, checks the announced grid sizes against
// a memory budget and the file size, and then decodes the grid payloads with
// samp's own bounded decoder (vdb_payload.h), which accepts only the layout
// WriteVdb writes. Files without the checksum (older samp files, other tools'
// files) are refused. docs/model_format.md describes the layout.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "libsamp/core/grid_spec.h"

namespace samp {

// A named dense float grid on a GridSpec.
struct DenseGrid {
  std::string name;
  std::vector<float> values;  // spec.NumVoxels(), x-fastest
};

// String-valued metadata (numbers and JSON are stored as their text).
using VdbMetadata = std::map<std::string, std::string>;

// Limits ReadVdb checks before any grid is decoded.
struct VdbReadOptions {
  // Most bytes the dense values of all grids may take (4 bytes per voxel and
  // grid); the decoded trees and the caller's copies take about as much again.
  int64_t max_dense_bytes = int64_t(512) << 20;
  // Most the dense values may exceed the file's size by (plus 1 MiB): samp's
  // SDF grids are dense and compress about 1:1, so a file announcing far more
  // is corrupt or hostile.
  double max_expansion = 64.0;

  // Throws samp::Error naming the field when an option is invalid.
  void Check() const;
};

// Initialises OpenVDB once (thread-safe, idempotent).
void InitializeOpenVdb();

// Writes `grids` (all on `spec`: same transform, voxel size = spec.voxel_size,
// index (i,j,k) at spec.Position(i,j,k)) with file-level `metadata`, atomically.
// Values equal to `background` may be left inactive.
void WriteVdb(const std::string& path, const GridSpec& spec, const std::vector<DenseGrid>& grids,
              const VdbMetadata& metadata, float background = 0.0f);

// Reads every FloatGrid of a .vdb written by WriteVdb back onto `*spec`
// (derived from the first grid's transform and the file metadata
// "samp_grid_dims"). Throws samp::Error naming the file on a missing, corrupt,
// truncated, inconsistent or foreign file, or one exceeding `options`.
// The returned metadata holds the file's string metadata, samp's reserved keys included.
std::vector<DenseGrid> ReadVdb(const std::string& path, GridSpec* spec, VdbMetadata* metadata,
                               const VdbReadOptions& options = VdbReadOptions());

}  // namespace samp
