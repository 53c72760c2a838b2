// Binary little-endian PLY output for meshes and point clouds (MeshLab,
// CloudCompare, Blender read it). Files are written atomically.
#pragma once

#include <cstdint>
#include <istream>
#include <string>
#include <vector>

#include "libsamp/core/mesh.h"

namespace samp {

void WritePly(const std::string& path, const Mesh& mesh);
void WritePly(const std::string& path, const PointCloud& cloud);

// Reads a point cloud written by WritePly (binary little-endian, vertex
// element with float x y z and optional uchar red green blue, in that order;
// other elements must be empty). Throws samp::Error naming the file when it
// is missing, truncated or of another layout.
PointCloud ReadPointCloudPly(const std::string& path);

// A PLY header: the lines between "ply" and "end_header". The one parser of
// it, for the point cloud reader above and the mesh loader's size checks
// (scan/mesh_io.cc), which hands the body to assimp.
struct PlyProperty {
  std::string type;        // a scalar's type; for a list, the type of its items
  std::string name;
  std::string count_type;  // a list's count type; "" for a scalar
};
struct PlyElement {
  std::string name;
  uint64_t count = 0;  // saturates at 2^62
  std::vector<PlyProperty> properties;
};
struct PlyHeader {
  std::string format;  // "ascii", "binary_little_endian" or "binary_big_endian"
  std::vector<PlyElement> elements;
  bool complete = false;  // end_header was read
};

// Reads header lines from `in` (the "ply" line already read) up to and
// including "end_header", or to the end of `in`. Strict: throws samp::Error
// starting with `what` (e.g. the file's path) and naming the line for a byte
// that is not printable ASCII, an unknown keyword, a format, element or
// property line of another shape, a type that is not a PLY type, a property
// before any element, or an element count that is not a number. (assimp's
// PLY reader loops forever on some such headers: tests/fuzz/regressions/mesh.)
PlyHeader ReadPlyHeader(std::istream& in, const std::string& what);

// Bytes of a PLY scalar type (char ... float64, int8 ... float64); throws
// samp::Error starting with `what` for any other name.
uint64_t PlyScalarBytes(const std::string& type, const std::string& what);

}  // namespace samp
