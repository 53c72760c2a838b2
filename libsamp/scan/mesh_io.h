// Loading CAD meshes with assimp (obj, ply, stl, off, 3ds, dae, gltf/glb, fbx,
// AC3D ac/acc, ...). The node hierarchy is flattened (node transforms applied),
// polygons triangulated, lines and points dropped. One format assimp lacks is
// read by samp itself: ApolloCar3D's car_models_json files (ReadApolloCarJson).
#pragma once

#include <string>
#include <vector>

#include "libsamp/core/mesh.h"

namespace samp {

// Throws samp::Error naming the file when it cannot be read or holds no triangles.
// A .json file is read by ReadApolloCarJson.
Mesh LoadMesh(const std::string& path);

// True when assimp has an importer for the file's extension (case-insensitive),
// or for a .json file whose first 64 KiB name a "vertices" or "faces" key
// (an ApolloCar3D model; manifests and other JSON files are not meshes).
bool IsMeshFile(const std::string& path);

// The mesh files (IsMeshFile) under `folder`, recursively, sorted by path and
// named through `folder` (symlinks kept in the names). Symlinked folders are
// followed, after the real ones, but each folder (by its canonical path) is
// walked once: a folder reached again through a link (a loop back to a
// parent, a second link to the same folder) is skipped with one warning
// naming the link and its target. Throws samp::Error naming the folder when
// `folder` is not a directory or a folder cannot be listed.
std::vector<std::string> ListMeshFiles(const std::string& folder);

// One ApolloCar3D car model (the dataset's car_models_json/<name>.json):
// a JSON object with "vertices" ([[x, y, z], ...] in metres) and "faces"
// ([[a, b, c], ...], 1-based vertex indices); other keys ("car_type", ...)
// are ignored. The mesh keeps the file's frame: box centred at 0, x across
// the car, y down, front at +z (canonical preset "apollocar3d" maps it,
// docs/canonical_frame.md). Throws samp::Error naming the file and the field
// (e.g. "faces[12]: index 0 is not 1-based").
Mesh ReadApolloCarJson(const std::string& path);

// Writes a mesh with assimp's exporter, format from the extension: .ply, .obj,
// .stl, .glb, .gltf. Written atomically. Throws samp::Error on failure.
void ExportMesh(const std::string& path, const Mesh& mesh);

}  // namespace samp
