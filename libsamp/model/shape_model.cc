#include "libsamp/model/shape_model.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/core/json_text.h"
#include "libsamp/core/log.h"
#include "libsamp/sdf/vdb_io.h"

namespace samp {
namespace {

// Metadata keys of the model file (docs/model_format.md). The grid keys
// samp_grid_dims / samp_grid_origin / samp_grid_voxel_size are written by WriteVdb.
constexpr char kFileTypeKey[] = "samp_file_type";
constexpr char kFileTypeShapeModel[] = "shape_model";
constexpr char kFormatVersionKey[] = "samp_format_version";
constexpr char kNumComponentsKey[] = "samp_num_components";
constexpr char kEigenvaluesKey[] = "samp_eigenvalues";
constexpr char kTotalVarianceKey[] = "samp_total_variance";
constexpr char kTrainingShapesKey[] = "samp_training_shapes";
constexpr char kOptionsKey[] = "samp_options";
constexpr char kChecksumKey[] = "samp_model_checksum";
constexpr char kMeanGrid[] = "mean";

// FNV-1a (64 bit) over the bytes of the grids' values (mean, pc_0, ...) and
// the eigenvalues: catches corruption that still decodes as a valid .vdb.
class Checksum {
 public:
  void Add(const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) {
      hash_ ^= p[i];
      hash_ *= 0x100000001b3ULL;
    }
  }
  // Floats equal to zero are hashed as +0 (the .vdb stores -0 as the background 0).
  void AddFloats(const float* values, int64_t n) {
    for (int64_t i = 0; i < n; ++i) {
      const float v = values[i] == 0.0f ? 0.0f : values[i];
      Add(&v, sizeof(v));
    }
  }
  std::string Hex() const {
    char buffer[17];
    std::snprintf(buffer, sizeof(buffer), "%016llx", static_cast<unsigned long long>(hash_));
    return buffer;
  }

 private:
  uint64_t hash_ = 0xcbf29ce484222325ULL;
};

std::string ModelChecksum(const Eigen::VectorXf& mean, const Eigen::MatrixXf& components,
                          const Eigen::VectorXd& eigenvalues) {
  Checksum checksum;
  checksum.AddFloats(mean.data(), mean.size());
  checksum.AddFloats(components.data(), components.size());
  checksum.Add(eigenvalues.data(), sizeof(double) * size_t(eigenvalues.size()));
  return checksum.Hex();
}

std::string ComponentGridName(int r) { return "pc_" + std::to_string(r); }

std::string GetMeta(const VdbMetadata& meta, const std::string& path, const char* key) {
  const auto it = meta.find(key);
  SAMP_CHECK(it != meta.end()) << path << ": model metadata '" << key << "' is missing";
  return it->second;
}

nlohmann::json ParseJsonMeta(const VdbMetadata& meta, const std::string& path, const char* key) {
  const std::string text = GetMeta(meta, path, key);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    SAMP_THROW() << path << ": model metadata '" << key << "' is not valid JSON: " << e.what();
  }
}

int ParseIntMeta(const VdbMetadata& meta, const std::string& path, const char* key) {
  const std::string text = GetMeta(meta, path, key);
  std::istringstream in(text);
  int value = 0;
  std::string rest;
  SAMP_CHECK((in >> value) && !(in >> rest))
      << path << ": model metadata '" << key << "' = '" << text << "' is not an integer";
  return value;
}

}  // namespace

Eigen::VectorXf ShapeModel::Shape(const Eigen::VectorXd& z) const {
  SAMP_CHECK(z.size() == NumComponents())
      << "ShapeModel::Shape: code has " << z.size() << " values, the model has "
      << NumComponents() << " components";
  return mean + components * z.cast<float>();
}

void ShapeModel::Check() const {
  grid.Check();
  const int64_t dim = grid.NumVoxels();
  SAMP_CHECK(mean.size() == dim) << "shape model: mean has " << mean.size()
                                 << " values, the grid (" << grid.ToString() << ") has " << dim;
  SAMP_CHECK(components.rows() == dim)
      << "shape model: components have " << components.rows() << " rows, the grid has " << dim;
  SAMP_CHECK(components.cols() >= 1) << "shape model: no components";
  SAMP_CHECK(eigenvalues.size() == components.cols())
      << "shape model: " << eigenvalues.size() << " eigenvalues for " << components.cols()
      << " components";
  SAMP_CHECK(mean.allFinite()) << "shape model: the mean has non-finite values";
  SAMP_CHECK(components.allFinite()) << "shape model: the components have non-finite values";
  SAMP_CHECK(eigenvalues.allFinite() && (eigenvalues.array() >= 0.0).all())
      << "shape model: eigenvalues must be finite and >= 0";
  SAMP_CHECK(std::isfinite(total_variance) && total_variance >= 0.0)
      << "shape model: total_variance must be finite and >= 0";
}

void ShapeModel::Save(const std::string& path) const {
  Check();
  nlohmann::json options;
  try {
    options = nlohmann::json::parse(options_json);
  } catch (const nlohmann::json::exception& e) {
    SAMP_THROW() << "shape model: options_json is not valid JSON: " << e.what();
  }
  const int num_components = NumComponents();
  std::vector<DenseGrid> grids(size_t(num_components) + 1);
  grids[0].name = kMeanGrid;
  grids[0].values.assign(mean.data(), mean.data() + mean.size());
  for (int r = 0; r < num_components; ++r) {
    grids[r + 1].name = ComponentGridName(r);
    const float* column = components.data() + int64_t(r) * components.rows();
    grids[r + 1].values.assign(column, column + components.rows());
  }
  VdbMetadata meta;
  meta[kFileTypeKey] = kFileTypeShapeModel;
  meta[kFormatVersionKey] = std::to_string(kFormatVersion);
  meta[kNumComponentsKey] = std::to_string(num_components);
  meta[kEigenvaluesKey] =
      DumpJson(nlohmann::json(std::vector<double>(eigenvalues.data(), eigenvalues.data() + num_components)));
  meta[kTotalVarianceKey] = DumpJson(nlohmann::json(total_variance));
  meta[kTrainingShapesKey] = DumpJson(nlohmann::json(training_shapes));
  meta[kOptionsKey] = DumpJson(options);
  meta[kChecksumKey] = ModelChecksum(mean, components, eigenvalues);
  WriteVdb(path, grid, grids, meta, /*background=*/0.0f);
}

ShapeModel ShapeModel::Load(const std::string& path, const VdbReadOptions& options) {
  GridSpec spec;
  VdbMetadata meta;
  std::vector<DenseGrid> grids = ReadVdb(path, &spec, &meta, options);

  const auto type_it = meta.find(kFileTypeKey);
  SAMP_CHECK(type_it != meta.end() || meta.count(kFormatVersionKey) > 0)
      << path << ": not a samp model file (no " << kFileTypeKey << " / " << kFormatVersionKey
      << " metadata)";
  SAMP_CHECK(type_it == meta.end() || type_it->second == kFileTypeShapeModel)
      << path << ": not a samp model file (" << kFileTypeKey << " is '" << type_it->second
      << "', expected '" << kFileTypeShapeModel << "')";
  const int version = ParseIntMeta(meta, path, kFormatVersionKey);
  SAMP_CHECK(version == kFormatVersion)
      << path << ": model format version " << version << ", this samp reads version "
      << kFormatVersion;

  ShapeModel model;
  model.grid = spec;
  const int num_components = ParseIntMeta(meta, path, kNumComponentsKey);
  SAMP_CHECK(num_components >= 1 && num_components <= 100000)
      << path << ": " << kNumComponentsKey << " = " << num_components << " is out of range";

  const nlohmann::json eigenvalues = ParseJsonMeta(meta, path, kEigenvaluesKey);
  SAMP_CHECK(eigenvalues.is_array()) << path << ": " << kEigenvaluesKey << " is not a JSON list";
  SAMP_CHECK(int(eigenvalues.size()) == num_components)
      << path << ": " << eigenvalues.size() << " eigenvalues for " << num_components
      << " components";
  model.eigenvalues.resize(num_components);
  for (int r = 0; r < num_components; ++r) {
    SAMP_CHECK(eigenvalues[r].is_number())
        << path << ": eigenvalue " << r << " is not a number: " << DumpJson(eigenvalues[r]);
    model.eigenvalues[r] = eigenvalues[r].get<double>();
  }
  if (meta.count(kTotalVarianceKey) > 0) {
    const nlohmann::json total = ParseJsonMeta(meta, path, kTotalVarianceKey);
    SAMP_CHECK(total.is_number()) << path << ": " << kTotalVarianceKey << " is not a number";
    model.total_variance = total.get<double>();
  }
  const nlohmann::json shapes = ParseJsonMeta(meta, path, kTrainingShapesKey);
  SAMP_CHECK(shapes.is_array()) << path << ": " << kTrainingShapesKey << " is not a JSON list";
  for (const auto& name : shapes) {
    SAMP_CHECK(name.is_string()) << path << ": " << kTrainingShapesKey
                                 << " holds a non-string entry " << DumpJson(name);
    model.training_shapes.push_back(name.get<std::string>());
  }
  model.options_json = DumpJson(ParseJsonMeta(meta, path, kOptionsKey));

  // Grids: mean and pc_0..pc_{R-1}, each exactly once; others are ignored.
  const int64_t dim = spec.NumVoxels();
  model.mean.resize(dim);
  model.components.resize(dim, num_components);
  std::vector<bool> found(size_t(num_components) + 1, false);
  for (const DenseGrid& g : grids) {
    int slot = -1;
    if (g.name == kMeanGrid) {
      slot = 0;
    } else if (g.name.rfind("pc_", 0) == 0) {
      std::istringstream in(g.name.substr(3));
      int r = -1;
      std::string rest;
      if ((in >> r) && !(in >> rest) && std::to_string(r) == g.name.substr(3)) {
        SAMP_CHECK(r >= 0 && r < num_components)
            << path << ": grid '" << g.name << "' but " << kNumComponentsKey << " = "
            << num_components;
        slot = r + 1;
      }
    }
    if (slot < 0) {
      LogDebug() << path << ": ignoring grid '" << g.name << "'";
      continue;
    }
    SAMP_CHECK(!found[slot]) << path << ": grid '" << g.name << "' appears twice";
    found[slot] = true;
    SAMP_CHECK(int64_t(g.values.size()) == dim)
        << path << ": grid '" << g.name << "' has " << g.values.size() << " values, expected "
        << dim;
    float* target = slot == 0 ? model.mean.data() : model.components.data() + (slot - 1) * dim;
    std::copy(g.values.begin(), g.values.end(), target);
  }
  for (int slot = 0; slot <= num_components; ++slot) {
    SAMP_CHECK(found[slot]) << path << ": grid '"
                            << (slot == 0 ? std::string(kMeanGrid) : ComponentGridName(slot - 1))
                            << "' is missing";
  }
  const std::string checksum = GetMeta(meta, path, kChecksumKey);
  SAMP_CHECK(checksum == ModelChecksum(model.mean, model.components, model.eigenvalues))
      << path << ": checksum mismatch (" << kChecksumKey << " = " << checksum
      << "): the file is corrupt";
  try {
    model.Check();
  } catch (const Error& e) {
    SAMP_THROW() << path << ": invalid model: " << e.what();
  }
  return model;
}

}  // namespace samp
