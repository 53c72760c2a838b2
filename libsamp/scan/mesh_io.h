// Loading CAD meshes with assimp (obj, ply, stl, off, 3ds, dae, gltf/glb, fbx,
// AC3D ac/acc, ...). The node hierarchy is flattened (node transforms applied),
// polygons triangulated, lines and points dropped.
#pragma once

#include <string>

#include "libsamp/core/mesh.h"

namespace samp {

// Throws samp::Error naming the file when it cannot be read or holds no triangles.
Mesh LoadMesh(const std::string& path);

// True when assimp has an importer for the file's extension (case-insensitive).
bool IsMeshFile(const std::string& path);

// Writes a mesh with assimp's exporter, format from the extension: .ply, .obj,
// .stl, .glb, .gltf. Written atomically. Throws samp::Error on failure.
void ExportMesh(const std::string& path, const Mesh& mesh);

}  // namespace samp
