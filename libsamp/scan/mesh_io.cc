#include "libsamp/scan/mesh_io.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <unistd.h>

#include <algorithm>
#include <assimp/Exporter.hpp>
#include <assimp/IOStream.hpp>
#include <assimp/IOSystem.hpp>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <system_error>
#include <vector>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/core/ply_io.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

std::string LowerExtension(const std::string& path) {
  std::string extension = fs::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return extension;
}

// Memory bounded by the input's size: assimp's OFF and PLY readers allocate
// the element counts of the header before they read a single element (a
// header "OFF\n99999999999999 4 6" asked for 49 GB under the fuzzer, a
// 43-byte "OFF200000000 ..." took 2.4 GB, a binary PLY declaring 10^8
// vertices with 100 bytes of body 1.26 GB). So samp reads these headers
// first, by content (whatever the extension), and refuses counts the file
// cannot hold: every element takes at least a known number of bytes.
uint64_t SaturatingMulAdd(uint64_t sum, uint64_t count, uint64_t bytes) {
  constexpr uint64_t kHuge = uint64_t(1) << 62;
  if (bytes != 0 && count > kHuge / bytes) return kHuge;
  return std::min(kHuge, sum + count * bytes);
}

// The decimal digits at `text[*i]` (at most 19 kept; more saturate).
uint64_t DigitRun(const std::string& text, size_t* i) {
  uint64_t value = 0;
  int digits = 0;
  while (*i < text.size() && text[*i] >= '0' && text[*i] <= '9') {
    if (++digits <= 18) value = value * 10 + uint64_t(text[*i] - '0');
    else value = uint64_t(1) << 62;
    ++*i;
  }
  return value;
}

std::string ReadHead(const std::string& path, size_t bytes) {
  std::ifstream in(path, std::ios::binary);
  std::string text(bytes, '\0');
  in.read(&text[0], std::streamsize(text.size()));
  text.resize(size_t(in.gcount()));
  return text;
}

// OFF: the keyword (OFF, COFF, NOFF, STOFF, 4OFF, nOFF, ... possibly glued to
// the first count), then the vertex and face counts. The first three runs of
// digits after the keyword are taken as counts, as assimp's number parser
// reads digits up to the first other character: "200000000x" is 200000000.
// Each vertex takes at least 6 bytes ("0 0 0\n"), each face 8 ("3 0 1 2\n").
void CheckOffHeaderFitsTheFile(const std::string& path, const std::string& text, uint64_t file_bytes) {
  size_t i = 0;
  while (i < text.size()) {  // comments and space before the keyword
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c == '#') {
      while (i < text.size() && text[i] != '\n') ++i;
    } else if (std::isspace(c)) {
      ++i;
    } else {
      break;
    }
  }
  const size_t keyword = text.find("OFF", i);
  if (keyword == std::string::npos || keyword > i + 4) return;  // not an OFF file
  uint64_t counts[3] = {0, 0, 0};
  int found = 0;
  for (size_t k = keyword + 3; k < text.size() && found < 3;) {
    if (text[k] == '#') {
      while (k < text.size() && text[k] != '\n') ++k;
    } else if (text[k] >= '0' && text[k] <= '9') {
      counts[found++] = DigitRun(text, &k);
    } else {
      ++k;
    }
  }
  const uint64_t needed = SaturatingMulAdd(SaturatingMulAdd(0, counts[0], 6), counts[1], 8);
  SAMP_CHECK(needed <= file_bytes && counts[2] <= file_bytes)
      << "cannot read mesh '" << path << "': its OFF header announces " << counts[0] << " vertices and "
      << counts[1] << " faces, at least " << needed << " bytes, but the file has " << file_bytes;
}

// PLY: "element NAME COUNT" and its "property TYPE NAME" / "property list
// COUNT_TYPE INDEX_TYPE NAME" lines up to "end_header". A binary element
// takes at least the sum of its scalar sizes plus each list's count size; an
// ASCII one 2 bytes per property (a digit and a separator). A count that is
// not a number, a header without an end_header line in its first 64 KiB, or
// an end_header without a line break after it, is an error here (assimp would
// guess, or loop).
void CheckPlyHeaderFitsTheFile(const std::string& path, const std::string& text, uint64_t file_bytes) {
  // assimp takes "ply" in any case as the magic (and loops on a garbled
  // header behind "plY" as behind "ply").
  if (text.size() < 3 || std::tolower(static_cast<unsigned char>(text[0])) != 'p' ||
      std::tolower(static_cast<unsigned char>(text[1])) != 'l' ||
      std::tolower(static_cast<unsigned char>(text[2])) != 'y') {
    return;
  }
  const std::string what = "cannot read mesh '" + path + "'";
  const size_t line_start = text.find("\nend_header");
  SAMP_CHECK(line_start != std::string::npos) << what << ": PLY header without end_header in its first "
                                              << text.size() << " bytes";
  const size_t end = line_start + 1;
  // "end_header" ends its line (assimp 5.2 loops forever on an ASCII body
  // that follows it on the same line).
  const size_t after = end + 10;
  const bool line_break = after >= text.size() || text[after] == '\n' ||
                          (text[after] == '\r' && (after + 1 >= text.size() || text[after + 1] == '\n'));
  SAMP_CHECK(line_break) << what << ": PLY 'end_header' is not followed by a line break (byte "
                         << int(static_cast<unsigned char>(text[after])) << " after it)";
  std::istringstream lines(text.substr(0, end));
  std::string magic;
  std::getline(lines, magic);
  const PlyHeader header = ReadPlyHeader(lines, what);
  const bool binary = header.format.rfind("binary", 0) == 0;
  uint64_t needed = 0;
  for (const PlyElement& element : header.elements) {
    uint64_t element_bytes = 0;
    for (const PlyProperty& p : element.properties)
      element_bytes += binary ? PlyScalarBytes(p.count_type.empty() ? p.type : p.count_type, what) : 2;
    needed = SaturatingMulAdd(needed, element.count, std::max<uint64_t>(element_bytes, 1));
  }
  const uint64_t body = file_bytes - std::min<uint64_t>(file_bytes, end + 10);
  SAMP_CHECK(needed <= body) << what << ": its PLY header announces elements of at least " << needed
                             << " bytes, but the file has " << body << " after its header";
}

void CheckHeaderCountsFitTheFile(const std::string& path) {
  std::error_code ec;
  const uint64_t file_bytes = fs::file_size(path, ec);
  if (ec) return;
  const std::string text = ReadHead(path, 65536);
  CheckOffHeaderFitsTheFile(path, text, file_bytes);
  CheckPlyHeaderFitsTheFile(path, text, file_bytes);
}

// Appends the triangles of every mesh referenced by `node` and its children,
// with the accumulated node transform applied.
void FlattenNode(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent_transform,
                 Mesh* out) {
  const aiMatrix4x4 transform = parent_transform * node.mTransformation;
  for (unsigned int k = 0; k < node.mNumMeshes; ++k) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[k]];
    if (!(mesh.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const int offset = int(out->vertices.size());
    out->vertices.reserve(out->vertices.size() + mesh.mNumVertices);
    for (unsigned int v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D p = transform * mesh.mVertices[v];
      out->vertices.emplace_back(p.x, p.y, p.z);
    }
    for (unsigned int f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // lines and points (SortByPType keeps them apart)
      out->triangles.emplace_back(offset + int(face.mIndices[0]), offset + int(face.mIndices[1]),
                                  offset + int(face.mIndices[2]));
    }
  }
  for (unsigned int c = 0; c < node.mNumChildren; ++c) {
    FlattenNode(scene, *node.mChildren[c], transform, out);
  }
}

// File output for assimp's exporters that checks every write: assimp's own
// file streams ignore what fwrite/fclose return, so a full disk left a
// truncated or empty mesh behind. The first failure (file and OS error) is
// kept in `*error`; writes after it are refused. Each file is flushed to the
// disk (fsync) when it is closed.
class CheckedFileStream : public Assimp::IOStream {
 public:
  CheckedFileStream(std::FILE* file, std::string path, std::shared_ptr<std::string> error)
      : file_(file), path_(std::move(path)), error_(std::move(error)) {}
  ~CheckedFileStream() override {
    if (std::fflush(file_) != 0) Fail("write to");
    if (::fsync(::fileno(file_)) != 0) Fail("fsync of");
    if (std::fclose(file_) != 0) Fail("close of");
  }
  size_t Read(void* buffer, size_t size, size_t count) override { return std::fread(buffer, size, count, file_); }
  size_t Write(const void* buffer, size_t size, size_t count) override {
    if (!error_->empty()) return 0;
    const size_t written = std::fwrite(buffer, size, count, file_);
    if (written != count) Fail("write to");
    return written;
  }
  aiReturn Seek(size_t offset, aiOrigin origin) override {
    const int whence = origin == aiOrigin_SET ? SEEK_SET : origin == aiOrigin_CUR ? SEEK_CUR : SEEK_END;
    return std::fseek(file_, long(offset), whence) == 0 ? aiReturn_SUCCESS : aiReturn_FAILURE;
  }
  size_t Tell() const override { return size_t(std::ftell(file_)); }
  size_t FileSize() const override {
    std::error_code ec;
    const uintmax_t size = fs::file_size(path_, ec);
    return ec ? 0 : size_t(size);
  }
  void Flush() override {
    if (std::fflush(file_) != 0) Fail("write to");
  }

 private:
  void Fail(const char* step) {
    if (error_->empty()) *error_ = std::string(step) + " " + path_ + " failed: " + std::strerror(errno ? errno : EIO);
  }
  std::FILE* file_;
  std::string path_;
  std::shared_ptr<std::string> error_;
};

class CheckedFileSystem : public Assimp::IOSystem {
 public:
  explicit CheckedFileSystem(std::shared_ptr<std::string> error) : error_(std::move(error)) {}
  bool Exists(const char* path) const override {
    std::error_code ec;
    return fs::exists(path, ec);
  }
  char getOsSeparator() const override { return '/'; }
  Assimp::IOStream* Open(const char* path, const char* mode) override {
    std::FILE* file = std::fopen(path, mode);
    if (file == nullptr) {
      if (error_->empty() && std::strchr(mode, 'w') != nullptr)
        *error_ = std::string("cannot create ") + path + ": " + std::strerror(errno);
      return nullptr;
    }
    return new CheckedFileStream(file, path, error_);
  }
  void Close(Assimp::IOStream* stream) override { delete stream; }

 private:
  std::shared_ptr<std::string> error_;
};

// The assimp exporter id for an output extension.
std::string ExportFormatId(const std::string& path) {
  const std::string extension = LowerExtension(path);
  if (extension == ".ply") return "plyb";
  if (extension == ".obj") return "objnomtl";
  if (extension == ".stl") return "stlb";
  if (extension == ".glb") return "glb2";
  if (extension == ".gltf") return "gltf2";
  SAMP_THROW() << "cannot export mesh to '" << path << "': unsupported extension '" << extension
               << "' (use .ply, .obj, .stl, .glb or .gltf)";
}

}  // namespace

Mesh ReadApolloCarJson(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  SAMP_CHECK(in.good()) << "cannot read ApolloCar3D model '" << path << "': cannot open the file";
  nlohmann::json j;
  try {
    in >> j;
  } catch (const nlohmann::json::exception& e) {
    SAMP_THROW() << "cannot read ApolloCar3D model '" << path << "': invalid JSON (" << e.what() << ")";
  }
  SAMP_CHECK(j.is_object()) << "ApolloCar3D model '" << path << "': the top level must be an object";
  for (const char* key : {"vertices", "faces"}) {
    SAMP_CHECK(j.contains(key) && j[key].is_array() && !j[key].empty())
        << "ApolloCar3D model '" << path << "': field '" << key << "' missing or not a non-empty array";
  }
  Mesh mesh;
  const nlohmann::json& vertices = j["vertices"];
  mesh.vertices.reserve(vertices.size());
  for (size_t v = 0; v < vertices.size(); ++v) {
    const nlohmann::json& p = vertices[v];
    SAMP_CHECK(p.is_array() && p.size() == 3 && p[0].is_number() && p[1].is_number() && p[2].is_number())
        << "ApolloCar3D model '" << path << "': vertices[" << v << "] is not three numbers";
    const Eigen::Vector3f q(p[0].get<float>(), p[1].get<float>(), p[2].get<float>());
    SAMP_CHECK(q.allFinite()) << "ApolloCar3D model '" << path << "': vertices[" << v << "] is not finite";
    mesh.vertices.push_back(q);
  }
  const nlohmann::json& faces = j["faces"];
  const int64_t n = int64_t(mesh.vertices.size());
  mesh.triangles.reserve(faces.size());
  for (size_t f = 0; f < faces.size(); ++f) {
    const nlohmann::json& t = faces[f];
    SAMP_CHECK(t.is_array() && t.size() == 3 && t[0].is_number_integer() && t[1].is_number_integer() &&
               t[2].is_number_integer())
        << "ApolloCar3D model '" << path << "': faces[" << f << "] is not three integers";
    Eigen::Vector3i triangle;
    for (int c = 0; c < 3; ++c) {
      const int64_t index = t[c].get<int64_t>();
      SAMP_CHECK(index >= 1) << "ApolloCar3D model '" << path << "': faces[" << f << "]: index " << index
                             << " is not 1-based";
      SAMP_CHECK(index <= n) << "ApolloCar3D model '" << path << "': faces[" << f << "]: index " << index
                             << " exceeds the " << n << " vertices";
      triangle[c] = int(index - 1);
    }
    mesh.triangles.push_back(triangle);
  }
  return mesh;
}

Mesh LoadMesh(const std::string& path) {
  std::error_code ec;
  SAMP_CHECK(fs::is_regular_file(path, ec)) << "cannot read mesh '" << path << "': no such file";
  if (LowerExtension(path) == ".json") return ReadApolloCarJson(path);
  CheckHeaderCountsFitTheFile(path);
  Assimp::Importer importer;
  // Drop lines and points entirely; keep only triangles after triangulation.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // Read and validate first, post-process after samp's own checks (what
  // ReadFile does with all flags at once, in the same order): assimp's
  // validation skips faces without indices, and its triangulation then
  // aborts the process on one (a mutated PLY did: an assertion in
  // TriangulateProcess).
  const aiScene* scene = importer.ReadFile(path, aiProcess_ValidateDataStructure);
  if (scene == nullptr) {
    SAMP_THROW() << "cannot read mesh '" << path << "': " << importer.GetErrorString();
  }
  for (unsigned int m = 0; m < scene->mNumMeshes; ++m)
    for (unsigned int f = 0; f < scene->mMeshes[m]->mNumFaces; ++f)
      SAMP_CHECK(scene->mMeshes[m]->mFaces[f].mNumIndices > 0)
          << "cannot read mesh '" << path << "': face " << f << " of mesh " << m << " has no vertex indices";
  scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                       aiProcess_SortByPType | aiProcess_FindDegenerates);
  if (scene == nullptr) {
    SAMP_THROW() << "cannot read mesh '" << path << "': " << importer.GetErrorString();
  }
  SAMP_CHECK(!(scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) && scene->mRootNode != nullptr)
      << "cannot read mesh '" << path << "': assimp returned an incomplete scene";
  Mesh mesh;
  FlattenNode(*scene, *scene->mRootNode, aiMatrix4x4(), &mesh);
  SAMP_CHECK(!mesh.triangles.empty()) << "mesh '" << path << "' holds no triangles";
  for (const Eigen::Vector3f& v : mesh.vertices) {
    SAMP_CHECK(v.allFinite()) << "mesh '" << path << "' has non-finite vertex coordinates";
  }
  return mesh;
}

std::vector<std::string> ListMeshFiles(const std::string& folder) {
  namespace fs = std::filesystem;
  std::error_code ec;
  SAMP_CHECK(fs::is_directory(folder, ec)) << "'" << folder << "' is not a directory";
  std::set<fs::path> walked;     // canonical paths of the folders walked
  std::deque<fs::path> pending;  // folders to walk; symlinked ones are appended
  pending.push_back(folder);
  std::vector<std::string> files;
  while (!pending.empty()) {
    const fs::path dir = pending.front();
    pending.pop_front();
    const fs::path canonical = fs::canonical(dir, ec);
    SAMP_CHECK(!ec) << "cannot resolve folder '" << dir.string() << "': " << ec.message();
    if (!walked.insert(canonical).second) {
      LogWarning() << "skipping '" << dir.string() << "': it leads to '" << canonical.string()
                   << "', a folder already walked (a symlink loop or a second link)";
      continue;
    }
    std::vector<fs::path> entries;
    for (fs::directory_iterator it(dir, ec); !ec && it != fs::directory_iterator(); it.increment(ec))
      entries.push_back(it->path());
    SAMP_CHECK(!ec) << "cannot list folder '" << dir.string() << "': " << ec.message();
    std::sort(entries.begin(), entries.end());
    std::vector<fs::path> real_dirs, linked_dirs;
    for (const fs::path& entry : entries) {
      if (fs::is_directory(entry, ec)) {
        (fs::is_symlink(entry, ec) ? linked_dirs : real_dirs).push_back(entry);
      } else if (fs::is_regular_file(entry, ec) && IsMeshFile(entry.string())) {
        files.push_back(entry.string());
      }
    }
    // Real subfolders first (depth first), links after every real folder.
    pending.insert(pending.begin(), real_dirs.begin(), real_dirs.end());
    pending.insert(pending.end(), linked_dirs.begin(), linked_dirs.end());
  }
  std::sort(files.begin(), files.end());
  return files;
}

bool IsMeshFile(const std::string& path) {
  const std::string extension = LowerExtension(path);
  if (extension.size() < 2) return false;
  if (extension == ".json") {
    std::ifstream in(path, std::ios::binary);
    std::string head(size_t(64) << 10, '\0');
    in.read(&head[0], std::streamsize(head.size()));
    head.resize(size_t(in.gcount()));
    return head.find("\"vertices\"") != std::string::npos || head.find("\"faces\"") != std::string::npos;
  }
  Assimp::Importer importer;
  return importer.IsExtensionSupported(extension);
}

void ExportMesh(const std::string& path, const Mesh& mesh) {
  const std::string format = ExportFormatId(path);
  SAMP_CHECK(!mesh.Empty()) << "cannot export an empty mesh to '" << path << "'";
  const int num_vertices = int(mesh.vertices.size());
  for (const Eigen::Vector3i& t : mesh.triangles) {
    SAMP_CHECK((t.array() >= 0).all() && (t.array() < num_vertices).all())
        << "cannot export mesh to '" << path << "': triangle index out of range";
  }

  // A minimal scene: one mesh, one default material, one root node. aiScene's
  // destructor frees everything allocated here.
  aiScene scene;
  scene.mNumMaterials = 1;
  scene.mMaterials = new aiMaterial*[1];
  scene.mMaterials[0] = new aiMaterial();
  scene.mNumMeshes = 1;
  scene.mMeshes = new aiMesh*[1];
  aiMesh* out = new aiMesh();
  scene.mMeshes[0] = out;
  out->mMaterialIndex = 0;
  out->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  out->mNumVertices = unsigned(num_vertices);
  out->mVertices = new aiVector3D[num_vertices];
  for (int v = 0; v < num_vertices; ++v) {
    out->mVertices[v] = aiVector3D(mesh.vertices[v].x(), mesh.vertices[v].y(), mesh.vertices[v].z());
  }
  out->mNumFaces = unsigned(mesh.triangles.size());
  out->mFaces = new aiFace[mesh.triangles.size()];
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    aiFace& face = out->mFaces[f];
    face.mNumIndices = 3;
    face.mIndices = new unsigned int[3];
    for (int c = 0; c < 3; ++c) face.mIndices[c] = unsigned(mesh.triangles[f][c]);
  }
  scene.mRootNode = new aiNode();
  scene.mRootNode->mNumMeshes = 1;
  scene.mRootNode->mMeshes = new unsigned int[1];
  scene.mRootNode->mMeshes[0] = 0;

  WriteFileAtomically(path, [&](const std::string& temporary_path) {
    // Some exporters (glTF) write side files named after the output (e.g. the
    // .bin buffer). Export into a private folder under the final file name, move
    // the side files beside the target, then hand the main file back.
    const fs::path target(path);
    const fs::path folder = fs::path(temporary_path).string() + ".d";
    std::error_code ec;
    fs::create_directories(folder, ec);
    SAMP_CHECK(!ec) << "cannot create " << folder.string() << ": " << ec.message();
    struct Cleanup {
      fs::path folder;
      ~Cleanup() {
        std::error_code ignored;
        fs::remove_all(folder, ignored);
      }
    } cleanup{folder};
    const fs::path main_file = folder / target.filename();
    Assimp::Exporter exporter;
    const auto write_error = std::make_shared<std::string>();
    exporter.SetIOHandler(new CheckedFileSystem(write_error));  // owned by the exporter
    const aiReturn exported = exporter.Export(&scene, format, main_file.string());
    SAMP_CHECK(write_error->empty()) << "cannot write '" << path << "': " << *write_error;
    if (exported != AI_SUCCESS) {
      SAMP_THROW() << "cannot export mesh to '" << path << "': " << exporter.GetErrorString();
    }
    SAMP_CHECK(fs::exists(main_file)) << "cannot export mesh to '" << path
                                      << "': assimp wrote no file";
    for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
      if (entry.path() == main_file) continue;
      const fs::path destination =
          (target.has_parent_path() ? target.parent_path() : fs::path(".")) / entry.path().filename();
      fs::rename(entry.path(), destination, ec);
      SAMP_CHECK(!ec) << "cannot move " << entry.path().string() << " to " << destination.string()
                      << ": " << ec.message();
    }
    fs::rename(main_file, temporary_path, ec);
    SAMP_CHECK(!ec) << "cannot move " << main_file.string() << " to " << temporary_path << ": "
                    << ec.message();
  });
}

}  // namespace samp
