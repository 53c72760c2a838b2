// Binary little-endian PLY output for meshes and point clouds (MeshLab,
// CloudCompare, Blender read it). Files are written atomically.
#pragma once

#include <string>

#include "libsamp/core/mesh.h"

namespace samp {

void WritePly(const std::string& path, const Mesh& mesh);
void WritePly(const std::string& path, const PointCloud& cloud);

// Reads a point cloud written by WritePly (binary little-endian, vertex
// element with float x y z and optional uchar red green blue, in that order;
// other elements must be empty). Throws samp::Error naming the file when it
// is missing, truncated or of another layout.
PointCloud ReadPointCloudPly(const std::string& path);

}  // namespace samp
