#include "libsamp/core/ply_io.h"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"

namespace samp {
namespace {

template <typename T>
void Put(std::ostream& out, const T& value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

// Some readers (assimp's binary PLY loader among them) skip whitespace after
// "end_header\n" and so lose the first data byte when it happens to be one
// (a float whose low byte is 0x0a, say): the rest of the file is then read
// misaligned. Writers put first a vertex whose first byte is not whitespace:
// the index of one (0 when the first already is).
size_t SafeFirstVertex(const std::vector<Eigen::Vector3f>& points) {
  for (size_t i = 0; i < points.size(); ++i) {
    unsigned char first;
    std::memcpy(&first, &points[i][0], 1);  // little-endian: the low byte of x
    if (!(first == ' ' || (first >= '\t' && first <= '\r'))) return i;
  }
  return 0;
}

}  // namespace

void WritePly(const std::string& path, const Mesh& mesh) {
  {
    std::ostringstream out(std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\ncomment samp mesh, object frame, metres\n"
        << "element vertex " << mesh.vertices.size() << "\n"
        << "property float x\nproperty float y\nproperty float z\n"
        << "element face " << mesh.triangles.size() << "\n"
        << "property list uchar int vertex_indices\nend_header\n";
    // Vertices 0 and `first` swap places (SafeFirstVertex).
    const int first = int(SafeFirstVertex(mesh.vertices));
    auto position = [&](int i) { return i == 0 ? first : i == first ? 0 : i; };
    for (int i = 0; i < int(mesh.vertices.size()); ++i) {
      for (int a = 0; a < 3; ++a) Put(out, mesh.vertices[size_t(position(i))][a]);
    }
    for (const Eigen::Vector3i& t : mesh.triangles) {
      Put(out, uint8_t(3));
      for (int a = 0; a < 3; ++a) Put(out, int32_t(position(t[a])));
    }
    WriteBytesAtomically(path, out.str());
  }
}

void WritePly(const std::string& path, const PointCloud& cloud) {
  const bool has_colors = !cloud.colors.empty();
  SAMP_CHECK(!has_colors || cloud.colors.size() == cloud.points.size())
      << "point cloud has " << cloud.colors.size() << " colours for " << cloud.points.size()
      << " points";
  {
    std::ostringstream out(std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\ncomment samp points, metres\n"
        << "element vertex " << cloud.points.size() << "\n"
        << "property float x\nproperty float y\nproperty float z\n";
    if (has_colors) out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    out << "end_header\n";
    const size_t first = SafeFirstVertex(cloud.points);
    for (size_t k = 0; k < cloud.points.size(); ++k) {
      const size_t i = k == 0 ? first : k == first ? 0 : k;  // points 0 and `first` swapped
      for (int a = 0; a < 3; ++a) Put(out, cloud.points[i][a]);
      if (has_colors) {
        for (int a = 0; a < 3; ++a) Put(out, cloud.colors[i][a]);
      }
    }
    WriteBytesAtomically(path, out.str());
  }
}

PlyHeader ReadPlyHeader(std::istream& in, const std::string& what) {
  PlyHeader header;
  int number = 1;  // the "ply" line
  for (std::string line; std::getline(in, line);) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line == "end_header") {
      header.complete = true;
      break;
    }
    const std::string at = what + ": PLY header line " + std::to_string(number);
    SAMP_CHECK(std::all_of(line.begin(), line.end(), [](char c) { return c == '\t' || (c >= ' ' && c <= '~'); }))
        << at << " has a byte that is not printable ASCII";
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string word; words >> word;) w.push_back(word);
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "format") {
      SAMP_CHECK(w.size() == 3 && (w[1] == "ascii" || w[1] == "binary_little_endian" || w[1] == "binary_big_endian"))
          << at << ": expected 'format ascii|binary_little_endian|binary_big_endian VERSION', got '" << line << "'";
      header.format = w[1];
    } else if (w[0] == "element") {
      SAMP_CHECK(w.size() == 3) << at << ": expected 'element NAME COUNT', got '" << line << "'";
      PlyElement element;
      element.name = w[1];
      const std::string& count = w[2];
      SAMP_CHECK(std::all_of(count.begin(), count.end(), [](char d) { return d >= '0' && d <= '9'; }))
          << what << ": PLY element '" << element.name << "' has count '" << count << "', not a number";
      for (size_t k = 0; k < count.size(); ++k)  // at most 18 digits kept; more saturate
        element.count = k < 18 ? element.count * 10 + uint64_t(count[k] - '0') : uint64_t(1) << 62;
      header.elements.push_back(std::move(element));
    } else if (w[0] == "property") {
      SAMP_CHECK(!header.elements.empty()) << at << ": a property before any element";
      PlyProperty property;
      if (w.size() == 5 && w[1] == "list") {
        property.count_type = w[2];
        property.type = w[3];
        property.name = w[4];
        PlyScalarBytes(property.count_type, at);
      } else {
        SAMP_CHECK(w.size() == 3 && w[1] != "list")
            << at << ": expected 'property TYPE NAME' or 'property list COUNT_TYPE TYPE NAME', got '" << line
            << "'";
        property.type = w[1];
        property.name = w[2];
      }
      PlyScalarBytes(property.type, at);  // throws for a name that is no PLY type
      header.elements.back().properties.push_back(std::move(property));
    } else {
      SAMP_THROW() << at << ": unknown keyword '" << w[0] << "' (expected format, comment, obj_info, element, "
                   << "property or end_header)";
    }
  }
  return header;
}

uint64_t PlyScalarBytes(const std::string& type, const std::string& what) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" ||
      type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  SAMP_THROW() << what << ": PLY property type '" << type << "' is not a PLY type";
}

PointCloud ReadPointCloudPly(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  SAMP_CHECK(in) << "cannot open " << path;
  std::string line;
  std::getline(in, line);
  SAMP_CHECK(line == "ply") << path << ": not a PLY file";
  const PlyHeader header = ReadPlyHeader(in, path);
  SAMP_CHECK(header.complete) << path << ": no end_header";
  SAMP_CHECK(header.format == "binary_little_endian") << path << ": only binary_little_endian PLY is read";
  const PlyElement* vertex = nullptr;
  for (const PlyElement& element : header.elements) {
    if (element.name == "vertex" && vertex == nullptr) {
      vertex = &element;
    } else {
      SAMP_CHECK(element.count == 0) << path << ": element " << element.name
                                     << " is not supported in a point cloud";
    }
  }
  SAMP_CHECK(vertex != nullptr) << path << ": no vertex element";
  std::vector<std::string> properties;
  for (const PlyProperty& p : vertex->properties)
    properties.push_back(p.count_type.empty() ? p.type + " " + p.name : "list");
  const std::vector<std::string> xyz = {"float x", "float y", "float z"};
  const std::vector<std::string> xyzrgb = {"float x", "float y", "float z", "uchar red", "uchar green", "uchar blue"};
  const bool has_colors = properties == xyzrgb;
  SAMP_CHECK(has_colors || properties == xyz)
      << path << ": vertex properties must be float x y z [uchar red green blue]";
  const uint64_t num_vertices = vertex->count;
  uint64_t available = 0;  // bytes after the header: a count the file cannot hold is refused before allocating
  {
    const std::streampos here = in.tellg();
    in.seekg(0, std::ios::end);
    available = uint64_t(in.tellg() - here);
    in.seekg(here);
  }
  const uint64_t point_bytes = has_colors ? 15 : 12;
  SAMP_CHECK(num_vertices <= available / point_bytes)
      << path << ": truncated: " << num_vertices << " points announced, " << available << " bytes after the header";
  PointCloud cloud;
  cloud.points.resize(size_t(num_vertices));
  if (has_colors) cloud.colors.resize(size_t(num_vertices));
  for (uint64_t i = 0; i < num_vertices; ++i) {
    in.read(reinterpret_cast<char*>(cloud.points[size_t(i)].data()), 3 * sizeof(float));
    if (has_colors) in.read(reinterpret_cast<char*>(cloud.colors[size_t(i)].data()), 3);
    SAMP_CHECK(in) << path << ": truncated after " << i << " of " << num_vertices << " points";
  }
  return cloud;
}

}  // namespace samp
