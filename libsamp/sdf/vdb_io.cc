#include "libsamp/sdf/vdb_io.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <set>
#include <sstream>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/sdf/byte_reader.h"
#include "libsamp/sdf/vdb_io_testing.h"
#include "libsamp/sdf/vdb_payload.h"

namespace samp {
namespace {

constexpr char kDimsKey[] = "samp_grid_dims";
constexpr char kOriginKey[] = "samp_grid_origin";
constexpr char kVoxelSizeKey[] = "samp_grid_voxel_size";
constexpr char kGridCountKey[] = "samp_grid_count";
// Per-grid metadata: checksum of the dense values, so that a truncated or
// corrupted file that OpenVDB itself reads without complaint is still caught.
constexpr char kChecksumKey[] = "samp_checksum";
// File metadata: the file's size (20 decimal digits) and FNV-1a 64 (16 hex
// digits) of all its bytes, these two values read as '0' digits; filled in
// after OpenVDB has written the file.
constexpr char kFileBytesKey[] = "samp_file_bytes";
constexpr char kFileChecksumKey[] = "samp_file_checksum";

using DenseXyz = openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ>;

std::string FormatDouble(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

// FNV-1a over the dense values (32-bit words); values equal to `background`
// (including -0 for a 0 background) hash as `background`, since they may be
// stored inactive and come back as the background.
std::string Checksum(const std::vector<float>& values, float background) {
  uint64_t hash = 1469598103934665603ull;
  uint32_t background_bits;
  std::memcpy(&background_bits, &background, sizeof(background_bits));
  for (float v : values) {
    uint32_t bits;
    if (v == background) {
      bits = background_bits;
    } else {
      std::memcpy(&bits, &v, sizeof(bits));
    }
    hash = (hash ^ bits) * 1099511628211ull;
  }
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%016llx", static_cast<unsigned long long>(hash));
  return buffer;
}

openvdb::math::Transform::Ptr MakeTransform(const GridSpec& spec) {
  auto transform = openvdb::math::Transform::createLinearTransform(spec.voxel_size);
  transform->postTranslate(openvdb::Vec3d(spec.origin.x(), spec.origin.y(), spec.origin.z()));
  return transform;
}

openvdb::CoordBBox SpecBBox(const GridSpec& spec) {
  return openvdb::CoordBBox(openvdb::Coord(0, 0, 0),
                            openvdb::Coord(spec.dims.x() - 1, spec.dims.y() - 1, spec.dims.z() - 1));
}

// Parses exactly `n` whitespace-separated numbers from `text`.
template <typename T>
bool ParseNumbers(const std::string& text, int n, T* out) {
  std::istringstream in(text);
  for (int i = 0; i < n; ++i) {
    if (!(in >> out[i])) return false;
  }
  std::string rest;
  return !(in >> rest);
}

// ---- samp's bounded reader ---------------------------------------------------
//
// OpenVDB's reader trusts every length in the file (a string length of 4 GB is
// allocated, a negative chunk size overflows a buffer in bloscFromStream), so
// samp reads every byte itself: the header, the file metadata and the grid
// descriptors here, the grid payloads in vdb_payload.cc. OpenVDB only writes.

constexpr int64_t kVdbMagic = 0x56444220;  // OPENVDB_MAGIC ("VDB ")
constexpr uint32_t kMinFileVersion = 222;  // OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION
constexpr int kUuidBytes = 36;
constexpr int32_t kMaxMetadataEntries = 4096;
constexpr int32_t kMaxGrids = 100001;
constexpr char kFloatTreeType[] = "Tree_float_5_4_3";
constexpr int64_t kExpansionSlackBytes = int64_t(1) << 20;

struct MetadataEntry {
  std::string type;
  std::string value;        // raw bytes (string metadata only)
  size_t value_offset = 0;  // in the file
  size_t value_size = 0;
};
using RawMetadata = std::map<std::string, MetadataEntry>;

// OpenVDB's MetaMap::writeMeta: int32 count, then name, type name and a
// uint32-sized value per entry.
RawMetadata ReadRawMetadata(ByteReader* in, const std::string& path, const char* where) {
  const int32_t count = in->Read<int32_t>("metadata count");
  SAMP_CHECK(count >= 0 && count <= kMaxMetadataEntries)
      << path << ": " << where << " holds " << count << " metadata entries (corrupt file?)";
  RawMetadata meta;
  for (int32_t i = 0; i < count; ++i) {
    const std::string name = in->ReadString("metadata name");
    MetadataEntry entry;
    entry.type = in->ReadString("metadata type");
    const uint32_t size = in->Read<uint32_t>("metadata size");
    entry.value_offset = in->pos();
    entry.value_size = size;
    // Values are kept for string metadata (all samp writes at file level).
    if (entry.type == "string") {
      entry.value = in->ReadBytes(size, "metadata value");
    } else {
      in->Skip(size, "metadata value");
    }
    meta[name] = std::move(entry);
  }
  return meta;
}

// Header and file metadata of a .vdb; `payload_offset` is the first byte after them.
struct VdbPrelude {
  RawMetadata file_meta;
  size_t payload_offset = 0;
};

VdbPrelude ReadPrelude(const std::string& bytes, const std::string& path) {
  ByteReader in(bytes, path);
  SAMP_CHECK(bytes.size() >= 8 && in.Read<int64_t>("magic number") == kVdbMagic)
      << path << ": not a .vdb file (no OpenVDB magic number)";
  const uint32_t file_version = in.Read<uint32_t>("file version");
  SAMP_CHECK(file_version >= kMinFileVersion && file_version <= openvdb::OPENVDB_FILE_VERSION)
      << path << ": OpenVDB file version " << file_version << ", samp reads " << kMinFileVersion
      << " to " << openvdb::OPENVDB_FILE_VERSION;
  in.Read<uint32_t>("library major version");
  in.Read<uint32_t>("library minor version");
  SAMP_CHECK(in.Read<char>("grid offsets flag") == 1)
      << path << ": the file has no grid offsets (not written by samp)";
  in.Skip(kUuidBytes, "UUID");
  VdbPrelude prelude;
  prelude.file_meta = ReadRawMetadata(&in, path, "the file");
  prelude.payload_offset = in.pos();
  return prelude;
}

const std::string* FindString(const RawMetadata& meta, const char* key) {
  const auto it = meta.find(key);
  if (it == meta.end() || it->second.type != "string") return nullptr;
  return &it->second.value;
}

// FNV-1a 64 of `bytes`, the bytes of the metadata values of `blanks` read as '0'.
uint64_t FileChecksum(const std::string& bytes, const RawMetadata& meta,
                      std::initializer_list<const char*> blanks) {
  std::vector<std::pair<size_t, size_t>> ranges;  // [begin, end), sorted
  for (const char* key : blanks) {
    const auto it = meta.find(key);
    if (it != meta.end()) {
      ranges.emplace_back(it->second.value_offset, it->second.value_offset + it->second.value_size);
    }
  }
  std::sort(ranges.begin(), ranges.end());
  uint64_t hash = 0xcbf29ce484222325ull;
  auto add = [&hash](const char* data, size_t n, bool blank) {
    for (size_t i = 0; i < n; ++i) {
      const unsigned char c = blank ? '0' : static_cast<unsigned char>(data[i]);
      hash = (hash ^ c) * 0x100000001b3ull;
    }
  };
  size_t pos = 0;
  for (const auto& [begin, end] : ranges) {
    if (begin < pos || end > bytes.size()) continue;
    add(bytes.data() + pos, begin - pos, false);
    add(nullptr, end - begin, true);
    pos = end;
  }
  add(bytes.data() + pos, bytes.size() - pos, false);
  return hash;
}

std::string Hex64(uint64_t value) {
  char buffer[17];
  std::snprintf(buffer, sizeof(buffer), "%016llx", static_cast<unsigned long long>(value));
  return buffer;
}

std::string Decimal20(uint64_t value) {
  char buffer[21];
  std::snprintf(buffer, sizeof(buffer), "%020llu", static_cast<unsigned long long>(value));
  return buffer;
}

// A grid as its descriptor and metadata describe it.
struct GridEntry {
  VdbGridPayloadRef payload;
  bool has_checksum = false;
  std::string checksum;  // samp_checksum of the dense values
};

// Everything samp checks before it decodes a grid: the file checksum, the grid
// descriptors, the announced sizes against the budget and file size. Returns
// where each grid's payload lies.
std::vector<GridEntry> ValidateBeforeDecoding(const std::string& bytes,
                                                      const std::string& path,
                                                      const VdbPrelude& prelude,
                                                      const VdbReadOptions& options,
                                                      VdbMetadata* meta_out,
                                                      Eigen::Vector3i* dims_out) {
  const RawMetadata& file_meta = prelude.file_meta;
  const std::string* checksum = FindString(file_meta, kFileChecksumKey);
  const std::string* file_bytes = FindString(file_meta, kFileBytesKey);
  if (checksum == nullptr || file_bytes == nullptr) {
    const std::string* version = FindString(file_meta, "samp_format_version");
    if (version != nullptr && FindString(file_meta, "samp_file_type") != nullptr) {
      SAMP_THROW() << path << ": a samp file of format version " << *version
                   << ", written before samp checksummed its files; samp does not decode "
                      "such files unverified: re-create it with this samp (samp train)";
    }
    SAMP_THROW() << path << ": not a samp .vdb file (no " << kFileChecksumKey
                 << "): samp reads only the checksummed files it writes";
  }
  SAMP_CHECK(*file_bytes == Decimal20(bytes.size()))
      << path << ": the file should be " << *file_bytes << " bytes long but is "
      << bytes.size() << " (truncated or corrupt)";
  const std::string actual =
      Hex64(FileChecksum(bytes, file_meta, {kFileBytesKey, kFileChecksumKey}));
  SAMP_CHECK(*checksum == actual) << path << ": checksum mismatch (" << kFileChecksumKey << " = "
                                  << *checksum << ", computed " << actual
                                  << "): the file is corrupt";

  // The bytes are what samp wrote; the announced sizes are still checked
  // against the budget before anything is expanded.
  VdbMetadata meta;
  for (const auto& [name, entry] : file_meta) {
    if (entry.type == "string") meta[name] = entry.value;
  }
  const auto dims_it = meta.find(kDimsKey);
  SAMP_CHECK(dims_it != meta.end()) << path << ": metadata " << kDimsKey << " is missing";
  int64_t dims[3];
  SAMP_CHECK(ParseNumbers(dims_it->second, 3, dims))
      << path << ": metadata " << kDimsKey << " = '" << dims_it->second
      << "' is not three integers";
  for (int a = 0; a < 3; ++a) {
    SAMP_CHECK(dims[a] >= 1 && dims[a] <= (int64_t(1) << 20))
        << path << ": metadata " << kDimsKey << " = '" << dims_it->second << "' is out of range";
  }
  const auto count_it = meta.find(kGridCountKey);
  SAMP_CHECK(count_it != meta.end()) << path << ": metadata " << kGridCountKey << " is missing";
  int64_t grid_count = 0;
  SAMP_CHECK(ParseNumbers(count_it->second, 1, &grid_count) && grid_count >= 1 &&
             grid_count < kMaxGrids)
      << path << ": metadata " << kGridCountKey << " = '" << count_it->second
      << "' is not a grid count";
  const double voxels = double(dims[0]) * double(dims[1]) * double(dims[2]);
  const double dense_bytes = voxels * double(grid_count) * sizeof(float);
  SAMP_CHECK(dense_bytes <= double(options.max_dense_bytes))
      << path << ": " << grid_count << " grids of " << dims[0] << " x " << dims[1] << " x "
      << dims[2] << " voxels would take " << dense_bytes / double(1 << 20)
      << " MiB, more than the memory budget of " << double(options.max_dense_bytes) / double(1 << 20)
      << " MiB (VdbReadOptions::max_dense_bytes)";
  SAMP_CHECK(dense_bytes <= options.max_expansion * double(bytes.size()) + kExpansionSlackBytes)
      << path << ": " << grid_count << " grids of " << dims[0] << " x " << dims[1] << " x "
      << dims[2] << " voxels (" << dense_bytes / double(1 << 20) << " MiB) from a "
      << bytes.size() << "-byte file: more than " << options.max_expansion
      << " times its size (corrupt file?)";

  ByteReader in(bytes, path);
  in.Seek(int64_t(prelude.payload_offset), "the grid count");
  const int32_t num_grids = in.Read<int32_t>("grid count");
  SAMP_CHECK(num_grids == grid_count)
      << path << ": the file should hold " << grid_count << " grids but has " << num_grids
      << " (truncated?)";
  std::set<std::string> names;
  std::vector<GridEntry> entries;
  int64_t previous_end = int64_t(in.pos());
  for (int32_t g = 0; g < num_grids; ++g) {
    const std::string name = in.ReadString("grid name");
    const std::string type = in.ReadString("grid type");
    const std::string parent = in.ReadString("grid instance parent");
    SAMP_CHECK(!name.empty() && names.insert(name).second)
        << path << ": grid " << g << " has an empty or repeated name";
    SAMP_CHECK(type == kFloatTreeType) << path << ": grid '" << name << "' is of type '" << type
                                       << "', expected " << kFloatTreeType;
    SAMP_CHECK(parent.empty()) << path << ": grid '" << name << "' is an instance of another grid";
    const int64_t grid_pos = in.Read<int64_t>("grid offset");
    const int64_t block_pos = in.Read<int64_t>("grid block offset");
    const int64_t end_pos = in.Read<int64_t>("grid end offset");
    SAMP_CHECK(grid_pos >= int64_t(in.pos()) && block_pos >= grid_pos && end_pos >= block_pos &&
               end_pos <= int64_t(bytes.size()) && grid_pos >= previous_end)
        << path << ": grid '" << name << "' has inconsistent offsets";
    in.Seek(grid_pos, "grid offset");
    GridEntry entry;
    VdbGridPayloadRef& ref = entry.payload;
    ref.name = name;
    ref.compression = in.Read<uint32_t>("grid compression");
    const RawMetadata grid_meta = ReadRawMetadata(&in, path, ("grid '" + name + "'").c_str());
    ref.transform = in.pos();
    ref.block = size_t(block_pos);
    ref.end = size_t(end_pos);
    if (const std::string* checksum = FindString(grid_meta, kChecksumKey)) {
      entry.has_checksum = true;
      entry.checksum = *checksum;
    }
    // The active bounding box OpenVDB recorded (min > max: an empty grid).
    int32_t box[2][3];
    bool has_box = true;
    const char* const box_keys[2] = {"file_bbox_min", "file_bbox_max"};
    for (int m = 0; m < 2; ++m) {
      const auto it = grid_meta.find(box_keys[m]);
      if (it == grid_meta.end()) {
        has_box = false;
        continue;
      }
      SAMP_CHECK(it->second.type == "vec3i" && it->second.value_size == 12)
          << path << ": grid '" << name << "' metadata " << box_keys[m] << " is not a vec3i";
      ByteReader value(bytes, path);
      value.Seek(int64_t(it->second.value_offset), box_keys[m]);
      for (int a = 0; a < 3; ++a) box[m][a] = value.Read<int32_t>(box_keys[m]);
    }
    const bool empty_box = has_box && (box[0][0] > box[1][0] || box[0][1] > box[1][1] ||
                                       box[0][2] > box[1][2]);
    if (has_box && !empty_box) {
      for (int a = 0; a < 3; ++a) {
        SAMP_CHECK(box[0][a] >= 0 && box[1][a] < dims[a])
            << path << ": grid '" << name << "' has active voxels " << box[0][a] << " to "
            << box[1][a] << " along axis " << a << ", outside the " << dims_it->second << " grid";
      }
    }
    const auto count = grid_meta.find("file_voxel_count");
    if (count != grid_meta.end() && count->second.type == "int64" && count->second.value_size == 8) {
      ByteReader value(bytes, path);
      value.Seek(int64_t(count->second.value_offset), "file_voxel_count");
      const int64_t n = value.Read<int64_t>("file_voxel_count");
      SAMP_CHECK(n >= 0 && double(n) <= voxels)
          << path << ": grid '" << name << "' announces " << n << " active voxels, the grid has "
          << int64_t(voxels);
      ref.announced_active_voxels = n;
    }
    entries.push_back(std::move(entry));
    previous_end = end_pos;
    in.Seek(end_pos, "grid end offset");
  }
  SAMP_CHECK(in.pos() == bytes.size())
      << path << ": " << (bytes.size() - in.pos()) << " bytes after the last grid (corrupt file)";
  *meta_out = std::move(meta);
  *dims_out = Eigen::Vector3i(int(dims[0]), int(dims[1]), int(dims[2]));
  return entries;
}

std::string ReadWholeFile(const std::string& path, const VdbReadOptions& options) {
  namespace fs = std::filesystem;
  std::error_code ec;
  SAMP_CHECK(fs::is_regular_file(path, ec)) << "cannot read " << path << ": no such file";
  const uintmax_t size = fs::file_size(path, ec);
  SAMP_CHECK(!ec) << "cannot read " << path << ": " << ec.message();
  SAMP_CHECK(size <= uintmax_t(options.max_dense_bytes + kExpansionSlackBytes))
      << path << ": " << size << " bytes, more than the memory budget of "
      << options.max_dense_bytes << " bytes (VdbReadOptions::max_dense_bytes) plus 1 MiB";
  std::ifstream in(path, std::ios::binary);
  SAMP_CHECK(in) << "cannot open " << path;
  std::string bytes(size_t(size), '\0');
  in.read(bytes.data(), std::streamsize(size));
  SAMP_CHECK(in && in.gcount() == std::streamsize(size)) << "cannot read " << path;
  SAMP_CHECK(in.peek() == std::ifstream::traits_type::eof())
      << path << ": the file grew while it was read";
  return bytes;
}

std::vector<DenseGrid> ReadVdbImpl(const std::string& path, GridSpec* spec, VdbMetadata* metadata,
                                   const VdbReadOptions& options,
                                   std::vector<VdbPayloadLayout>* layouts = nullptr) {
  options.Check();
  const std::string bytes = ReadWholeFile(path, options);
  const VdbPrelude prelude = ReadPrelude(bytes, path);
  VdbMetadata meta;
  GridSpec result;
  const std::vector<GridEntry> grids =
      ValidateBeforeDecoding(bytes, path, prelude, options, &meta, &result.dims);
  SAMP_CHECK(!grids.empty()) << path << ": the file holds no grids";

  // Verified: samp's bounded decoder reads the payloads from memory (not the
  // path, which could have changed since). Grid geometry from the first
  // grid's transform; all grids must share it exactly.
  std::vector<DenseGrid> out;
  out.reserve(grids.size());
  if (layouts != nullptr) layouts->assign(grids.size(), VdbPayloadLayout());
  VdbGridTransform first_transform;
  for (size_t g = 0; g < grids.size(); ++g) {
    const VdbGridPayloadRef& ref = grids[g].payload;
    DenseGrid dense_grid;
    dense_grid.name = ref.name;
    VdbGridTransform transform;
    float background = 0.0f;
    DecodeVdbFloatGrid(bytes, path, ref, result.dims, &dense_grid.values, &transform,
                       &background, layouts != nullptr ? &(*layouts)[g] : nullptr);
    if (g == 0) {
      first_transform = transform;
      result.voxel_size = transform.voxel_size;
      result.origin = transform.origin;
    } else {
      SAMP_CHECK(transform.serialized == first_transform.serialized)
          << path << ": grid '" << ref.name << "' does not share the transform of grid '"
          << grids[0].payload.name << "'";
    }
    // The per-grid checksum over the dense values (the file checksum is no
    // signature; this one catches decoding mistakes and older corruptions).
    if (grids[g].has_checksum) {
      SAMP_CHECK(grids[g].checksum == Checksum(dense_grid.values, background))
          << path << ": grid '" << dense_grid.name
          << "' fails its checksum (truncated or corrupt file)";
    }
    out.push_back(std::move(dense_grid));
  }
  const auto origin_it = meta.find(kOriginKey);
  if (origin_it != meta.end()) {
    double origin[3];
    SAMP_CHECK(ParseNumbers(origin_it->second, 3, origin))
        << path << ": metadata " << kOriginKey << " = '" << origin_it->second
        << "' is not three numbers";
    const Eigen::Vector3d stored(origin[0], origin[1], origin[2]);
    SAMP_CHECK((stored - result.origin).cwiseAbs().maxCoeff() < 1e-6 * std::max(1.0, stored.norm()))
        << path << ": metadata " << kOriginKey << " = '" << origin_it->second
        << "' disagrees with the grid transform";
  }
  try {
    result.Check();
  } catch (const Error& e) {
    SAMP_THROW() << path << ": invalid grid: " << e.what();
  }
  if (spec != nullptr) *spec = result;
  if (metadata != nullptr) *metadata = std::move(meta);
  return out;
}

// Fills in the size and checksum of a file OpenVDB has just written into
// `bytes` (their placeholders have the final length, so no offset moves).
// `path` names the file in errors.
void SealBytes(std::string* bytes, const std::string& path) {
  const VdbPrelude prelude = ReadPrelude(*bytes, path);
  const auto size_it = prelude.file_meta.find(kFileBytesKey);
  const auto checksum_it = prelude.file_meta.find(kFileChecksumKey);
  SAMP_CHECK(size_it != prelude.file_meta.end() && checksum_it != prelude.file_meta.end())
      << "cannot write " << path << ": checksum placeholders missing";
  const std::string size_text = Decimal20(bytes->size());
  const std::string checksum_text =
      Hex64(FileChecksum(*bytes, prelude.file_meta, {kFileBytesKey, kFileChecksumKey}));
  SAMP_CHECK(size_it->second.value.size() == size_text.size() &&
             checksum_it->second.value.size() == checksum_text.size())
      << "cannot write " << path << ": checksum placeholders have the wrong length";
  bytes->replace(size_t(size_it->second.value_offset), size_text.size(), size_text);
  bytes->replace(size_t(checksum_it->second.value_offset), checksum_text.size(), checksum_text);
}

// OpenVDB's archive writer into memory: the bytes io::File writes (the same
// Archive::write with seekable = true, offsets counted from 0), but samp
// writes them to the disk itself, checking every write (io::File does not
// report a full disk: it left a truncated file behind).
class MemoryArchive : public openvdb::io::Archive {
 public:
  std::string Write(const openvdb::GridPtrVec& grids, const openvdb::MetaMap& meta) const {
    std::ostringstream out(std::ios::binary);
    Archive::write(out, grids, /*seekable=*/true, meta);
    SAMP_CHECK(out) << "OpenVDB's writer failed";
    return out.str();
  }
};

}  // namespace

void InitializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

namespace {

// WriteVdb with the io::COMPRESS_* flags to store the values with.
void WriteVdbImpl(const std::string& path, const GridSpec& spec,
                  const std::vector<DenseGrid>& grids, const VdbMetadata& metadata,
                  float background, uint32_t compression) {
  InitializeOpenVdb();
  spec.Check();
  SAMP_CHECK(!grids.empty()) << "WriteVdb " << path << ": no grids to write";
  std::set<std::string> names;
  for (const DenseGrid& g : grids) {
    SAMP_CHECK(!g.name.empty()) << "WriteVdb " << path << ": a grid has an empty name";
    SAMP_CHECK(names.insert(g.name).second)
        << "WriteVdb " << path << ": grid name '" << g.name << "' is used twice";
    SAMP_CHECK(int64_t(g.values.size()) == spec.NumVoxels())
        << "WriteVdb " << path << ": grid '" << g.name << "' has " << g.values.size()
        << " values, the grid spec needs " << spec.NumVoxels();
  }

  const openvdb::math::Transform::Ptr transform = MakeTransform(spec);
  const openvdb::CoordBBox bbox = SpecBBox(spec);
  openvdb::GridPtrVec vdb_grids;
  for (const DenseGrid& g : grids) {
    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(background);
    grid->setName(g.name);
    grid->setTransform(transform);
    // copyFromDense only reads the dense buffer.
    DenseXyz dense(bbox, const_cast<float*>(g.values.data()));
    openvdb::tools::copyFromDense(dense, *grid, /*tolerance=*/0.0f);
    grid->insertMeta(kChecksumKey, openvdb::StringMetadata(Checksum(g.values, background)));
    vdb_grids.push_back(grid);
  }

  openvdb::MetaMap file_meta;
  for (const auto& [key, value] : metadata) {
    file_meta.insertMeta(key, openvdb::StringMetadata(value));
  }
  std::ostringstream dims;
  dims << spec.dims.x() << " " << spec.dims.y() << " " << spec.dims.z();
  file_meta.insertMeta(kDimsKey, openvdb::StringMetadata(dims.str()));
  file_meta.insertMeta(kOriginKey, openvdb::StringMetadata(FormatDouble(spec.origin.x()) + " " +
                                                           FormatDouble(spec.origin.y()) + " " +
                                                           FormatDouble(spec.origin.z())));
  file_meta.insertMeta(kGridCountKey, openvdb::StringMetadata(std::to_string(grids.size())));
  file_meta.insertMeta(kVoxelSizeKey, openvdb::StringMetadata(FormatDouble(spec.voxel_size)));
  file_meta.insertMeta(kFileBytesKey, openvdb::StringMetadata(Decimal20(0)));
  file_meta.insertMeta(kFileChecksumKey, openvdb::StringMetadata(Hex64(0)));

  std::string bytes;
  try {
    MemoryArchive archive;
    archive.setCompression(compression);
    bytes = archive.Write(vdb_grids, file_meta);
  } catch (const openvdb::Exception& e) {
    SAMP_THROW() << "cannot write " << path << ": " << e.what();
  } catch (const std::exception& e) {
    SAMP_THROW() << "cannot write " << path << ": " << e.what();
  }
  // Size and checksum of exactly these bytes; every one of them is written
  // and checked, then the file is read back and verified before it replaces
  // `path`.
  SealBytes(&bytes, path);
  WriteBytesAtomically(path, bytes, [&](const std::string& temporary) {
    VdbReadOptions verify;
    verify.max_dense_bytes = std::max<int64_t>(
        verify.max_dense_bytes, int64_t(grids.size()) * spec.NumVoxels() * int64_t(sizeof(float)));
    verify.max_expansion = 1e15;  // the writer knows its grids: a constant grid compresses very well
    try {
      SAMP_CHECK(ReadWholeFile(temporary, verify) == bytes) << "its bytes differ from those written";
      ReadVdbImpl(temporary, nullptr, nullptr, verify);
    } catch (const std::exception& e) {
      SAMP_THROW() << "cannot write " << path << ": the written file " << temporary
                   << " does not read back: " << e.what();
    }
  });
}

}  // namespace

void WriteVdb(const std::string& path, const GridSpec& spec, const std::vector<DenseGrid>& grids,
              const VdbMetadata& metadata, float background) {
  // The layout ReadVdb's decoder reads (vdb_payload.h): blosc when OpenVDB
  // has it, else zip, with active-value mask compression; full floats.
  WriteVdbImpl(path, spec, grids, metadata, background,
               (openvdb::io::Archive::hasBloscCompression() ? openvdb::io::COMPRESS_BLOSC
                                                            : openvdb::io::COMPRESS_ZIP) |
                   openvdb::io::COMPRESS_ACTIVE_MASK);
}

void WriteVdbForTesting(const std::string& path, const GridSpec& spec,
                        const std::vector<DenseGrid>& grids, const VdbMetadata& metadata,
                        float background, VdbTestCompression compression) {
  const uint32_t codec = compression == VdbTestCompression::kBlosc ? openvdb::io::COMPRESS_BLOSC
                                                                   : openvdb::io::COMPRESS_ZIP;
  WriteVdbImpl(path, spec, grids, metadata, background, codec | openvdb::io::COMPRESS_ACTIVE_MASK);
}

void ResealVdbForTesting(const std::string& path) {
  std::string bytes = ReadWholeFile(path, VdbReadOptions());
  SealBytes(&bytes, path);
  WriteBytesChecked(path, bytes);
}

std::vector<VdbPayloadLayout> VdbPayloadLayoutForTesting(const std::string& path) {
  std::vector<VdbPayloadLayout> layouts;
  ReadVdbImpl(path, nullptr, nullptr, VdbReadOptions(), &layouts);
  return layouts;
}

void VdbReadOptions::Check() const {
  SAMP_CHECK(max_dense_bytes > 0) << "VdbReadOptions: max_dense_bytes must be > 0, got "
                                  << max_dense_bytes;
  SAMP_CHECK(std::isfinite(max_expansion) && max_expansion >= 1.0)
      << "VdbReadOptions: max_expansion must be >= 1, got " << max_expansion;
}

std::vector<DenseGrid> ReadVdb(const std::string& path, GridSpec* spec, VdbMetadata* metadata,
                               const VdbReadOptions& options) {
  try {
    return ReadVdbImpl(path, spec, metadata, options);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    SAMP_THROW() << "cannot read " << path << " (corrupt or truncated .vdb file?): " << e.what();
  } catch (...) {
    SAMP_THROW() << "cannot read " << path << ": unknown error";
  }
}

}  // namespace samp
