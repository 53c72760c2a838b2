// Binary little-endian PLY output for meshes and point clouds (MeshLab,
// CloudCompare, Blender read it). Files are written atomically.
#pragma once

#include <string>

#include "libsamp/core/mesh.h"

namespace samp {

void WritePly(const std::string& path, const Mesh& mesh);
void WritePly(const std::string& path, const PointCloud& cloud);

}  // namespace samp
