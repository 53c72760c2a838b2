#include "libsamp/model/shape_model.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "libsamp/core/error.h"
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

// The cell of the grid that a point falls in (after clamping to the grid box),
// its 8 corner sample indices and the trilinear coordinates within the cell.
struct Cell {
  int64_t index[8];     // corner c = dx + 2 dy + 4 dz
  double t[3];          // position within the cell, [0, 1]
  bool clamped[3];      // the point lies outside the box along this axis
  double outside[3];    // point - nearest box point, metres
};

// Returns false for a non-finite point.
inline bool Locate(const GridSpec& grid, const double* point, Cell* cell) {
  int i[3];
  const double h = grid.voxel_size;
  for (int a = 0; a < 3; ++a) {
    const double x = (point[a] - grid.origin[a]) / h;
    if (!std::isfinite(x)) return false;
    const double x_max = double(grid.dims[a] - 1);
    double xc = x;
    cell->clamped[a] = false;
    cell->outside[a] = 0.0;
    if (x < 0.0) {
      xc = 0.0;
      cell->clamped[a] = true;
      cell->outside[a] = point[a] - grid.origin[a];
    } else if (x > x_max) {
      xc = x_max;
      cell->clamped[a] = true;
      cell->outside[a] = point[a] - (grid.origin[a] + x_max * h);
    }
    // xc >= 0, so truncation is floor; the last sample belongs to the last cell.
    i[a] = std::min(int(xc), grid.dims[a] - 2);
    cell->t[a] = xc - i[a];
  }
  const int64_t stride_y = grid.dims.x();
  const int64_t stride_z = int64_t(grid.dims.x()) * grid.dims.y();
  const int64_t base = grid.Index(i[0], i[1], i[2]);
  for (int c = 0; c < 8; ++c) {
    cell->index[c] = base + (c & 1) + ((c >> 1) & 1) * stride_y + ((c >> 2) & 1) * stride_z;
  }
  return true;
}

inline void Weights(const Cell& cell, double* w) {
  const double tx = cell.t[0], ty = cell.t[1], tz = cell.t[2];
  const double wx[2] = {1.0 - tx, tx}, wy[2] = {1.0 - ty, ty}, wz[2] = {1.0 - tz, tz};
  for (int c = 0; c < 8; ++c) w[c] = wx[c & 1] * wy[(c >> 1) & 1] * wz[(c >> 2) & 1];
}

// Trilinear value of the corner values v plus, when d_point != null, its exact
// gradient; then the outside-the-box continuation (docs/model_format.md).
inline double Interpolate(const GridSpec& grid, const Cell& cell, const double* w,
                          const double* v, double* d_point) {
  double value = 0.0;
  for (int c = 0; c < 8; ++c) value += w[c] * v[c];
  double distance_squared = 0.0;
  for (int a = 0; a < 3; ++a) distance_squared += cell.outside[a] * cell.outside[a];
  const double distance = std::sqrt(distance_squared);
  if (d_point != nullptr) {
    const double tx = cell.t[0], ty = cell.t[1], tz = cell.t[2];
    // Differences along x, y, z of the four cell edges, weighted by the other two coordinates.
    const double dx = (1 - ty) * (1 - tz) * (v[1] - v[0]) + ty * (1 - tz) * (v[3] - v[2]) +
                      (1 - ty) * tz * (v[5] - v[4]) + ty * tz * (v[7] - v[6]);
    const double dy = (1 - tx) * (1 - tz) * (v[2] - v[0]) + tx * (1 - tz) * (v[3] - v[1]) +
                      (1 - tx) * tz * (v[6] - v[4]) + tx * tz * (v[7] - v[5]);
    const double dz = (1 - tx) * (1 - ty) * (v[4] - v[0]) + tx * (1 - ty) * (v[5] - v[1]) +
                      (1 - tx) * ty * (v[6] - v[2]) + tx * ty * (v[7] - v[3]);
    const double inv_h = 1.0 / grid.voxel_size;
    const double d[3] = {dx * inv_h, dy * inv_h, dz * inv_h};
    for (int a = 0; a < 3; ++a) {
      // Along a clamped axis the box point does not move with the point; the
      // distance term grows instead.
      d_point[a] = cell.clamped[a] ? cell.outside[a] / distance : d[a];
    }
  }
  return value + distance;
}

inline void SetNaN(int n, double* out) {
  if (out == nullptr) return;
  for (int i = 0; i < n; ++i) out[i] = std::numeric_limits<double>::quiet_NaN();
}

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

double ShapeModel::Evaluate(const Eigen::VectorXd& z, const Eigen::Vector3d& point,
                            Eigen::Vector3d* d_point, Eigen::VectorXd* d_z) const {
  SAMP_CHECK(z.size() == NumComponents())
      << "ShapeModel::Evaluate: code has " << z.size() << " values, the model has "
      << NumComponents() << " components";
  if (d_z != nullptr && d_z->size() != NumComponents()) d_z->resize(NumComponents());
  return Evaluate(z.data(), point.data(), d_point != nullptr ? d_point->data() : nullptr,
                  d_z != nullptr ? d_z->data() : nullptr);
}

double ShapeModel::Evaluate(const double* z, const double* point, double* d_point,
                            double* d_z) const {
  const int num_components = NumComponents();
  Cell cell;
  if (!Locate(grid, point, &cell)) {
    SetNaN(3, d_point);
    SetNaN(num_components, d_z);
    return std::numeric_limits<double>::quiet_NaN();
  }
  double w[8];
  Weights(cell, w);
  double v[8];
  const float* mu = mean.data();
  for (int c = 0; c < 8; ++c) v[c] = mu[cell.index[c]];
  const int64_t dim = components.rows();
  for (int r = 0; r < num_components; ++r) {
    const float* column = components.data() + r * dim;
    double corner[8];
    for (int c = 0; c < 8; ++c) corner[c] = column[cell.index[c]];
    const double z_r = z[r];
    double gradient = 0.0;
    for (int c = 0; c < 8; ++c) {
      v[c] += corner[c] * z_r;
      gradient += w[c] * corner[c];
    }
    if (d_z != nullptr) d_z[r] = gradient;
  }
  return Interpolate(grid, cell, w, v, d_point);
}

double ShapeModel::EvaluateDense(const float* shape, const double* point, double* d_point) const {
  Cell cell;
  if (!Locate(grid, point, &cell)) {
    SetNaN(3, d_point);
    return std::numeric_limits<double>::quiet_NaN();
  }
  double w[8];
  Weights(cell, w);
  double v[8];
  for (int c = 0; c < 8; ++c) v[c] = shape[cell.index[c]];
  return Interpolate(grid, cell, w, v, d_point);
}

void ShapeModel::CodeGradient(const double* point, double* d_z) const {
  const int num_components = NumComponents();
  Cell cell;
  if (!Locate(grid, point, &cell)) {
    SetNaN(num_components, d_z);
    return;
  }
  double w[8];
  Weights(cell, w);
  const int64_t dim = components.rows();
  for (int r = 0; r < num_components; ++r) {
    const float* column = components.data() + r * dim;
    double gradient = 0.0;
    for (int c = 0; c < 8; ++c) gradient += w[c] * column[cell.index[c]];
    d_z[r] = gradient;
  }
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
      nlohmann::json(std::vector<double>(eigenvalues.data(), eigenvalues.data() + num_components))
          .dump();
  meta[kTotalVarianceKey] = nlohmann::json(total_variance).dump();
  meta[kTrainingShapesKey] = nlohmann::json(training_shapes).dump();
  meta[kOptionsKey] = options.dump();
  meta[kChecksumKey] = ModelChecksum(mean, components, eigenvalues);
  WriteVdb(path, grid, grids, meta, /*background=*/0.0f);
}

ShapeModel ShapeModel::Load(const std::string& path) {
  GridSpec spec;
  VdbMetadata meta;
  std::vector<DenseGrid> grids = ReadVdb(path, &spec, &meta);

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
        << path << ": eigenvalue " << r << " is not a number: " << eigenvalues[r].dump();
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
                                 << " holds a non-string entry " << name.dump();
    model.training_shapes.push_back(name.get<std::string>());
  }
  model.options_json = ParseJsonMeta(meta, path, kOptionsKey).dump();

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
