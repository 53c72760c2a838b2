// Surface extraction from dense signed distance fields on a GridSpec: the
// isosurface (zero level set by default) as a triangle mesh, with OpenVDB's
// dual-contouring mesher (tools::volumeToMesh, adaptivity 0).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "libsamp/core/grid_spec.h"
#include "libsamp/core/mesh.h"

namespace samp {

// Extracts the `isovalue` level set of `values` (grid.NumVoxels() samples,
// x-fastest, negative inside). The mesh is in the grid's (object) frame, in
// metres; quads are split into two triangles; triangles face outwards (their
// normals point towards increasing values). Outside the grid the field is taken
// as positive (outside), so a shape cut by the grid border is closed there
// (the closing cap lies within one voxel outside the grid box).
// Returns an empty mesh when the field does not cross the isovalue.
// Throws samp::Error when values.size() != grid.NumVoxels() or the grid is invalid.
// Thread-safe (no shared state besides OpenVDB's one-time initialisation).
Mesh ExtractSurface(const GridSpec& grid, const std::vector<float>& values, double isovalue = 0.0);
Mesh ExtractSurface(const GridSpec& grid, const Eigen::VectorXf& values, double isovalue = 0.0);

// Total enclosed volume of a closed, outward-oriented triangle mesh (m^3), by
// the divergence theorem; negative when the triangles face inwards.
double SignedVolume(const Mesh& mesh);

}  // namespace samp
