#include "libsamp/sdf/vdb_io.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <set>
#include <sstream>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"

namespace samp {
namespace {

constexpr char kDimsKey[] = "samp_grid_dims";
constexpr char kOriginKey[] = "samp_grid_origin";
constexpr char kVoxelSizeKey[] = "samp_grid_voxel_size";
constexpr char kGridCountKey[] = "samp_grid_count";
// Per-grid metadata: checksum of the dense values, so that a truncated or
// corrupted file that OpenVDB itself reads without complaint is still caught.
constexpr char kChecksumKey[] = "samp_checksum";

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

// Checks that `transform` maps index space to world space as an axis-aligned
// uniform scale plus translation, and returns its voxel size and the world
// position of index (0,0,0).
void DecomposeTransform(const openvdb::math::Transform& transform, const std::string& path,
                        const std::string& grid_name, double* voxel_size, Eigen::Vector3d* origin) {
  SAMP_CHECK(transform.isLinear()) << path << ": grid '" << grid_name
                                   << "' has a non-linear transform";
  const openvdb::Vec3d o = transform.indexToWorld(openvdb::Vec3d(0, 0, 0));
  const openvdb::Vec3d ex = transform.indexToWorld(openvdb::Vec3d(1, 0, 0)) - o;
  const openvdb::Vec3d ey = transform.indexToWorld(openvdb::Vec3d(0, 1, 0)) - o;
  const openvdb::Vec3d ez = transform.indexToWorld(openvdb::Vec3d(0, 0, 1)) - o;
  const double h = ex.x();
  const double tol = 1e-9 * std::max(1.0, std::abs(h));
  const bool axis_aligned_uniform = h > 0 && std::abs(ex.y()) < tol && std::abs(ex.z()) < tol &&
                                    std::abs(ey.x()) < tol && std::abs(ey.y() - h) < tol &&
                                    std::abs(ey.z()) < tol && std::abs(ez.x()) < tol &&
                                    std::abs(ez.y()) < tol && std::abs(ez.z() - h) < tol;
  SAMP_CHECK(axis_aligned_uniform) << path << ": grid '" << grid_name
                                   << "' is not on an axis-aligned uniform voxel grid";
  *voxel_size = h;
  *origin = Eigen::Vector3d(o.x(), o.y(), o.z());
}

std::vector<DenseGrid> ReadVdbImpl(const std::string& path, GridSpec* spec, VdbMetadata* metadata) {
  namespace fs = std::filesystem;
  std::error_code ec;
  SAMP_CHECK(fs::is_regular_file(path, ec)) << "cannot read " << path << ": no such file";

  openvdb::io::File file(path);
  // No delayed loading: every read error must surface here, not lazily later.
  file.open(/*delayLoad=*/false);
  openvdb::MetaMap::Ptr file_meta = file.getMetadata();
  openvdb::GridPtrVecPtr grids = file.getGrids();
  file.close();
  SAMP_CHECK(grids && !grids->empty()) << path << ": the file holds no grids";

  VdbMetadata meta;
  if (file_meta) {
    for (auto it = file_meta->beginMeta(); it != file_meta->endMeta(); ++it) {
      meta[it->first] = it->second ? it->second->str() : std::string();
    }
  }

  // Grid geometry from the first grid's transform; all grids must share it.
  GridSpec result;
  const std::string first_name = (*grids)[0]->getName();
  DecomposeTransform((*grids)[0]->transform(), path, first_name, &result.voxel_size,
                     &result.origin);
  for (const auto& base : *grids) {
    SAMP_CHECK(base->isType<openvdb::FloatGrid>())
        << path << ": grid '" << base->getName() << "' is a " << base->valueType()
        << " grid, expected float";
    SAMP_CHECK(base->transform() == (*grids)[0]->transform())
        << path << ": grid '" << base->getName() << "' does not share the transform of grid '"
        << first_name << "'";
  }

  const auto count_it = meta.find(kGridCountKey);
  if (count_it != meta.end()) {
    SAMP_CHECK(count_it->second == std::to_string(grids->size()))
        << path << ": the file should hold " << count_it->second << " grids but has "
        << grids->size() << " (truncated?)";
  }

  const auto dims_it = meta.find(kDimsKey);
  if (dims_it != meta.end()) {
    int dims[3];
    SAMP_CHECK(ParseNumbers(dims_it->second, 3, dims))
        << path << ": metadata " << kDimsKey << " = '" << dims_it->second
        << "' is not three integers";
    result.dims = Eigen::Vector3i(dims[0], dims[1], dims[2]);
  } else {
    // A foreign file: the grid is the union of the active bounding boxes.
    openvdb::CoordBBox bbox;
    for (const auto& base : *grids) bbox.expand(base->evalActiveVoxelBoundingBox());
    SAMP_CHECK(!bbox.empty()) << path << ": no " << kDimsKey
                              << " metadata and no active voxels to derive the grid from";
    const openvdb::Vec3d o = (*grids)[0]->transform().indexToWorld(bbox.min());
    result.origin = Eigen::Vector3d(o.x(), o.y(), o.z());
    const openvdb::Coord d = bbox.dim();
    result.dims = Eigen::Vector3i(d.x(), d.y(), d.z());
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

  // Index offset of the dense box in the grids' index space (non-zero only
  // for foreign files whose active box does not start at index 0).
  const openvdb::Vec3d offset_world =
      (*grids)[0]->transform().worldToIndex(openvdb::Vec3d(result.origin.x(), result.origin.y(),
                                                           result.origin.z()));
  const openvdb::Coord offset(int(std::lround(offset_world.x())), int(std::lround(offset_world.y())),
                              int(std::lround(offset_world.z())));
  const openvdb::CoordBBox bbox(offset, offset + openvdb::Coord(result.dims.x() - 1,
                                                                result.dims.y() - 1,
                                                                result.dims.z() - 1));

  std::vector<DenseGrid> out;
  out.reserve(grids->size());
  for (const auto& base : *grids) {
    const auto grid = openvdb::gridConstPtrCast<openvdb::FloatGrid>(base);
    DenseGrid dense_grid;
    dense_grid.name = grid->getName();
    dense_grid.values.assign(size_t(result.NumVoxels()), grid->background());
    DenseXyz dense(bbox, dense_grid.values.data());
    openvdb::tools::copyToDense(*grid, dense);
    const auto checksum = grid->getMetadata<openvdb::StringMetadata>(kChecksumKey);
    if (checksum) {
      SAMP_CHECK(checksum->value() == Checksum(dense_grid.values, grid->background()))
          << path << ": grid '" << dense_grid.name
          << "' fails its checksum (truncated or corrupt file)";
    }
    out.push_back(std::move(dense_grid));
  }
  if (spec != nullptr) *spec = result;
  if (metadata != nullptr) *metadata = std::move(meta);
  return out;
}

}  // namespace

void InitializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

void WriteVdb(const std::string& path, const GridSpec& spec, const std::vector<DenseGrid>& grids,
              const VdbMetadata& metadata, float background) {
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

  WriteFileAtomically(path, [&](const std::string& temporary) {
    try {
      openvdb::io::File file(temporary);
      file.setCompression((openvdb::io::Archive::hasBloscCompression() ? openvdb::io::COMPRESS_BLOSC
                                                                       : openvdb::io::COMPRESS_ZIP) |
                          openvdb::io::COMPRESS_ACTIVE_MASK);
      file.write(vdb_grids, file_meta);
      file.close();
    } catch (const openvdb::Exception& e) {
      SAMP_THROW() << "cannot write " << path << ": " << e.what();
    } catch (const std::exception& e) {
      SAMP_THROW() << "cannot write " << path << ": " << e.what();
    }
  });
}

std::vector<DenseGrid> ReadVdb(const std::string& path, GridSpec* spec, VdbMetadata* metadata) {
  InitializeOpenVdb();
  try {
    return ReadVdbImpl(path, spec, metadata);
  } catch (const Error&) {
    throw;
  } catch (const openvdb::Exception& e) {
    SAMP_THROW() << "cannot read " << path << " (corrupt or not a .vdb file?): " << e.what();
  } catch (const std::exception& e) {
    SAMP_THROW() << "cannot read " << path << " (corrupt or truncated .vdb file?): " << e.what();
  } catch (...) {
    SAMP_THROW() << "cannot read " << path << ": unknown error";
  }
}

}  // namespace samp
