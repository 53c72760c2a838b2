// Dense grids <-> OpenVDB FloatGrids, and .vdb files (written atomically).
// Only this layer and model/ include OpenVDB headers.
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

// Initialises OpenVDB once (thread-safe, idempotent).
void InitializeOpenVdb();

// Writes `grids` (all on `spec`: same transform, voxel size = spec.voxel_size,
// index (i,j,k) at spec.Position(i,j,k)) with file-level `metadata`, atomically.
// Values equal to `background` may be left inactive.
void WriteVdb(const std::string& path, const GridSpec& spec, const std::vector<DenseGrid>& grids,
              const VdbMetadata& metadata, float background = 0.0f);

// Reads every FloatGrid of a .vdb back onto `*spec` (derived from the first
// grid's transform and the file metadata "samp_grid_dims"). Throws samp::Error
// on a missing, corrupt, truncated or inconsistent file.
std::vector<DenseGrid> ReadVdb(const std::string& path, GridSpec* spec, VdbMetadata* metadata);

}  // namespace samp
