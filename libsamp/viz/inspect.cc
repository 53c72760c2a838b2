#include "libsamp/viz/inspect.h"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numeric>
#include <random>
#include <set>
#include <sstream>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/core/json_text.h"
#include "libsamp/core/log.h"
#include "libsamp/core/nearest_neighbor.h"
#include "libsamp/core/util.h"
#include "libsamp/model/trainer.h"
#include "libsamp/scan/mesh_io.h"
#include "libsamp/scan/renderer.h"
#include "libsamp/sdf/vdb_io.h"
#include "libsamp/viz/inspect_option_table.h"
#include "libsamp/viz/opencv_image.h"
#include "libsamp/viz/plot.h"
#include "libsamp/sdf/surface.h"

namespace samp {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

std::string Format(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

bool IsVdbFile(const std::string& path) { return Lower(fs::path(path).extension().string()) == ".vdb"; }

double Sigma(const ShapeModel& model, int i) { return std::sqrt(std::max(0.0, model.eigenvalues[i])); }

// mu + k sigma_i w_i as a dense field.
Eigen::VectorXf EigenShape(const ShapeModel& model, int component, double k) {
  Eigen::VectorXd z = Eigen::VectorXd::Zero(model.NumComponents());
  z[component] = k * Sigma(model, component);
  return model.Shape(z);
}

std::string SignedK(double k) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%+.1f", k);
  return buffer;
}

// The scan and SDF options the model was trained with (its stored trainer
// options, model/trainer.h TrainOptionsFromJson: a missing key is an error).
void TrainingOptions(const ShapeModel& model, ScanOptions* scan, SdfOptions* sdf) {
  const TrainOptions options =
      TrainOptionsFromJson(model.options_json, "the model's trainer options (metadata samp_options)");
  *scan = options.scan;
  *sdf = options.sdf;
}

// Canonicalisation options for a CAD file from a manifest (entry or defaults).
CanonicalizeOptions CanonicalizeFor(const std::string& path, const std::string& manifest_path,
                                    std::string* name) {
  *name = fs::path(path).stem().string();
  if (manifest_path.empty()) return CanonicalizeOptions();
  const Manifest manifest = LoadManifest(manifest_path);
  const fs::path manifest_dir = fs::path(manifest_path).parent_path();
  std::error_code ec;
  const std::string relative = fs::relative(path, manifest_dir, ec).generic_string();
  const ManifestEntry* entry = nullptr;
  if (!ec && !relative.empty()) entry = manifest.Find(relative);
  if (entry == nullptr) entry = manifest.Find(fs::path(path).filename().string());
  if (entry == nullptr) return manifest.defaults;
  if (!entry->name.empty()) *name = entry->name;
  return entry->canonicalize;
}

// Input files of a folder (recursively, sorted) or the file itself.
std::vector<std::string> ListInputs(const std::string& input) {
  std::error_code ec;
  SAMP_CHECK(fs::exists(input, ec)) << "cannot read " << input << ": no such file or folder";
  if (!fs::is_directory(input, ec)) return {input};
  std::vector<std::string> files;
  for (auto it = fs::recursive_directory_iterator(input, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    if (!it->is_regular_file()) continue;
    const std::string path = it->path().string();
    if (IsVdbFile(path) || IsMeshFile(path)) files.push_back(path);
  }
  std::sort(files.begin(), files.end());
  SAMP_CHECK(!files.empty()) << input << " holds no mesh or .vdb files";
  return files;
}

DistanceStats StatsOf(std::vector<double> d) {
  DistanceStats stats;
  stats.count = int64_t(d.size());
  if (d.empty()) return stats;
  std::sort(d.begin(), d.end());
  stats.mean = std::accumulate(d.begin(), d.end(), 0.0) / d.size();
  stats.median = d[d.size() / 2];
  stats.p95 = d[std::min(d.size() - 1, size_t(std::ceil(0.95 * d.size())) - 1)];
  stats.max = d.back();
  return stats;
}

std::vector<Eigen::Vector3f> Subsample(const std::vector<Eigen::Vector3f>& points, int count,
                                       uint64_t seed) {
  if (int(points.size()) <= count) return points;
  std::vector<size_t> index(points.size());
  std::iota(index.begin(), index.end(), 0);
  std::mt19937_64 rng(seed);
  std::shuffle(index.begin(), index.end(), rng);
  std::vector<Eigen::Vector3f> result;
  result.reserve(count);
  for (int i = 0; i < count; ++i) result.push_back(points[index[i]]);
  return result;
}

}  // namespace

// ---- Summary ------------------------------------------------------------------

std::string SummarizeModel(const ShapeModel& model, const std::string& path) {
  std::ostringstream out;
  const GridSpec& g = model.grid;
  const Eigen::Vector3d lo = g.MinCorner(), hi = g.MaxCorner();
  char line[512];
  out << "samp shape model (format version " << ShapeModel::kFormatVersion << ")\n";
  if (!path.empty()) out << "  file             " << path << "\n";
  std::snprintf(line, sizeof(line),
                "  grid             %d x %d x %d = %lld voxels, voxel size %.4g m\n"
                "  extent (object)  x [%.3f, %.3f]  y [%.3f, %.3f]  z [%.3f, %.3f] m"
                "  (%.2f x %.2f x %.2f m)\n",
                g.dims.x(), g.dims.y(), g.dims.z(), (long long)g.NumVoxels(), g.voxel_size, lo.x(),
                hi.x(), lo.y(), hi.y(), lo.z(), hi.z(), hi.x() - lo.x(), hi.y() - lo.y(),
                hi.z() - lo.z());
  out << line;
  const int r = model.NumComponents();
  out << "  components R     " << r << "\n";
  const double kept = model.eigenvalues.sum();
  const bool has_total = model.total_variance > 0.0;
  const double denominator = has_total ? model.total_variance : kept;
  if (has_total) {
    std::snprintf(line, sizeof(line),
                  "  eigenvalues      (explained = share of the total variance %.6g m^2 of the "
                  "training SDFs; the R components keep %.1f %%)\n",
                  model.total_variance, 100.0 * kept / model.total_variance);
  } else {
    std::snprintf(line, sizeof(line),
                  "  eigenvalues      (the file stores no total variance: explained is relative to "
                  "the kept R components, sum %.6g m^2)\n",
                  kept);
  }
  out << line;
  std::snprintf(line, sizeof(line), "    %3s  %14s  %12s  %10s  %10s\n", "i", "lambda_i [m^2]",
                "sigma_i [m]", "explained", "cumulative");
  out << line;
  double cumulative = 0.0;
  for (int i = 0; i < r; ++i) {
    const double share = denominator > 0 ? model.eigenvalues[i] / denominator : 0.0;
    cumulative += share;
    std::snprintf(line, sizeof(line), "    %3d  %14.6g  %12.4f  %9.2f%%  %9.2f%%\n", i + 1,
                  model.eigenvalues[i], Sigma(model, i), 100.0 * share, 100.0 * cumulative);
    out << line;
  }
  out << "  training shapes  " << model.training_shapes.size() << "\n";
  std::string row = "    ";
  for (size_t i = 0; i < model.training_shapes.size(); ++i) {
    const std::string item = model.training_shapes[i] + (i + 1 < model.training_shapes.size() ? ", " : "");
    if (row.size() + item.size() > 96) {
      out << row << "\n";
      row = "    ";
    }
    row += item;
  }
  if (row.size() > 4) out << row << "\n";
  out << "  trainer options";
  try {
    const Json options = Json::parse(model.options_json);
    std::istringstream pretty(DumpJson(options, 2));
    std::string text_line;
    out << "\n";
    while (std::getline(pretty, text_line)) out << "    " << text_line << "\n";
  } catch (const Json::exception&) {
    out << "  (not valid JSON) " << model.options_json << "\n";
  }
  return out.str();
}

// ---- Eigen-shape meshes -----------------------------------------------------------

void EigenShapeMeshOptions::Check() const {
  EigenShapeMeshOptionTable().Check(*this);
}

std::string EigenShapeMeshSummary::BriefReport() const {
  std::ostringstream out;
  out << "wrote " << files.size() << " meshes";
  if (!files.empty()) out << " (" << fs::path(files.front()).parent_path().string() << ")";
  out << "\n";
  for (const auto& f : files) out << "  " << fs::path(f).filename().string() << "\n";
  for (const auto& e : empty) out << "  " << e << ": empty zero level set, not written\n";
  return out.str();
}

EigenShapeMeshSummary WriteEigenShapeMeshes(const ShapeModel& model,
                                            const EigenShapeMeshOptions& options) {
  options.Check();
  model.Check();
  const int r = options.max_components > 0 ? std::min(options.max_components, model.NumComponents())
                                           : model.NumComponents();
  struct Item {
    std::string name;
    int component;
    double k;
  };
  std::vector<Item> items = {{"mean", 0, 0.0}};
  for (int i = 0; i < r; ++i) {
    for (double k : options.ks) {
      if (k != 0.0) items.push_back({"pc" + std::to_string(i + 1) + "_" + SignedK(k) + "sd", i, k});
    }
  }
  std::vector<Mesh> meshes(items.size());
  tbb::parallel_for(size_t(0), items.size(), [&](size_t i) {
    meshes[i] = ExtractSurface(model.grid, EigenShape(model, items[i].component, items[i].k));
  });
  EigenShapeMeshSummary summary;
  for (size_t i = 0; i < items.size(); ++i) {
    if (meshes[i].Empty()) {
      summary.empty.push_back(items[i].name);
      continue;
    }
    const std::string path =
        (fs::path(options.output_folder) / (items[i].name + "." + options.format)).string();
    ExportMesh(path, meshes[i]);
    summary.files.push_back(path);
  }
  return summary;
}

// ---- Encoding ---------------------------------------------------------------------

void EncodeOptions::Check() const {
  EncodeOptionTable().Check(*this);
}

ShapeInput LoadShapeInput(const std::string& path, const ShapeModel& model,
                          const std::string& manifest_path) {
  ShapeInput input;
  input.file = path;
  if (IsVdbFile(path)) {
    input.kind = "sdf";
    GridSpec spec;
    VdbMetadata metadata;
    std::vector<DenseGrid> grids = ReadVdb(path, &spec, &metadata);
    SAMP_CHECK(!grids.empty()) << path << ": no float grid";
    SAMP_CHECK(spec == model.grid) << path << ": its grid (" << spec.ToString()
                                   << ") differs from the model's (" << model.grid.ToString() << ")";
    size_t chosen = 0;
    for (size_t i = 0; i < grids.size(); ++i) {
      if (grids[i].name == "sdf") chosen = i;
    }
    if (grids.size() > 1 && grids[chosen].name != "sdf") {
      SAMP_THROW() << path << ": holds " << grids.size()
                   << " grids and none named 'sdf' (a model file? pass per-model SDFs)";
    }
    input.sdf = std::move(grids[chosen].values);
    input.name = metadata.count("samp_name") ? metadata["samp_name"] : fs::path(path).stem().string();
    if (metadata.count("samp_source_file")) input.source_file = metadata["samp_source_file"];
    input.original = ExtractSurface(model.grid, input.sdf);
    SAMP_CHECK(!input.original.Empty()) << path << ": the SDF has no zero level set";
    input.original_points = input.original.vertices;
    return input;
  }
  input.kind = "cad";
  const CanonicalizeOptions canonicalize = CanonicalizeFor(path, manifest_path, &input.name);
  const CanonicalizeResult canonical = CanonicalCad(path, canonicalize);
  for (const auto& warning : canonical.warnings) LogWarning() << path << ": " << warning;
  ScanOptions scan_options;
  SdfOptions sdf_options;
  TrainingOptions(model, &scan_options, &sdf_options);
  ScannedSdf scanned;
  try {
    scanned = ScanToSdf(canonical.mesh, scan_options, model.grid, sdf_options);
  } catch (const Error& e) {
    SAMP_THROW() << path << ": " << e.what();
  }
  SAMP_CHECK(scanned.sdf.summary.sign_ok) << path << ": sign carving failed (inside fraction "
                                          << scanned.sdf.summary.inside_fraction << ")";
  input.sdf = std::move(scanned.sdf.values);
  input.original = canonical.mesh;
  input.original_points = scanned.scan.SurfacePoints().points;
  return input;
}

std::vector<Eigen::Vector3f> SampleSurface(const Mesh& mesh, int count, uint64_t seed) {
  std::vector<Eigen::Vector3f> points;
  if (mesh.Empty() || count <= 0) return points;
  std::vector<double> cumulative(mesh.triangles.size());
  double total = 0.0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const Eigen::Vector3d a = mesh.vertices[tri[0]].cast<double>();
    total += 0.5 * (mesh.vertices[tri[1]].cast<double>() - a)
                       .cross(mesh.vertices[tri[2]].cast<double>() - a)
                       .norm();
    cumulative[t] = total;
  }
  if (!(total > 0)) return points;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  points.reserve(count);
  for (int i = 0; i < count; ++i) {
    const double pick = uniform(rng) * total;
    const size_t t = std::min(size_t(std::lower_bound(cumulative.begin(), cumulative.end(), pick) -
                                     cumulative.begin()),
                              cumulative.size() - 1);
    const auto& tri = mesh.triangles[t];
    const double s = std::sqrt(uniform(rng)), u = uniform(rng);
    const Eigen::Vector3f p = float(1 - s) * mesh.vertices[tri[0]] +
                              float(s * (1 - u)) * mesh.vertices[tri[1]] +
                              float(s * u) * mesh.vertices[tri[2]];
    points.push_back(p);
  }
  return points;
}

DistanceStats NearestDistances(const std::vector<Eigen::Vector3f>& from,
                               const std::vector<Eigen::Vector3f>& to) {
  if (from.empty() || to.empty()) return DistanceStats();
  return StatsOf(NearestDistanceEach(from, to));
}

std::vector<double> NearestDistanceEach(const std::vector<Eigen::Vector3f>& from,
                                        const std::vector<Eigen::Vector3f>& to) {
  if (to.empty()) return std::vector<double>(from.size(), std::numeric_limits<double>::infinity());
  if (from.empty()) return {};
  // The nearest-neighbour grid of core/nearest_neighbor.h over `to`, about 100
  // cells along its longest side, searching as far as the farthest query.
  std::vector<Eigen::Vector3d> reference(to.size());
  Eigen::Vector3d lo = to[0].cast<double>(), hi = lo;
  for (size_t i = 0; i < to.size(); ++i) {
    reference[i] = to[i].cast<double>();
    lo = lo.cwiseMin(reference[i]), hi = hi.cwiseMax(reference[i]);
  }
  Eigen::Vector3d all_lo = lo, all_hi = hi;
  for (const auto& p : from) all_lo = all_lo.cwiseMin(p.cast<double>()), all_hi = all_hi.cwiseMax(p.cast<double>());
  const double cell = std::max(1e-4, (hi - lo).maxCoeff() / 100.0);
  const RadiusNearestNeighbor index(reference, (all_hi - all_lo).norm() + cell, cell);
  std::vector<double> distances(from.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, from.size()), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t q = range.begin(); q != range.end(); ++q) distances[q] = index.Distance(from[q].cast<double>());
  });
  return distances;
}

namespace {

std::string FormatStats(const DistanceStats& s) {
  return Format("%.4f", s.mean) + " / " + Format("%.4f", s.p95);
}

}  // namespace

std::string EncodeSummary::BriefReport() const {
  std::ostringstream out;
  size_t name_width = 5;
  for (const auto& s : shapes) name_width = std::max(name_width, s.name.size());
  char line[1024];
  std::snprintf(line, sizeof(line), "%-*s  %-4s  %11s  %9s  %-17s  %-17s  %s\n", int(name_width),
                "shape", "kind", "rms_near[m]", "rms_all[m]", "acc mean/95%[m]",
                "compl mean/95%[m]", "code z / sigma");
  out << line;
  for (const auto& s : shapes) {
    if (!s.ok) {
      std::snprintf(line, sizeof(line), "%-*s  %-4s  failed: %s\n", int(name_width), s.name.c_str(),
                    s.kind.c_str(), s.error.c_str());
      out << line;
      continue;
    }
    std::string code;
    for (int i = 0; i < s.code_in_sigmas.size(); ++i) {
      code += (i ? " " : "") + Format("%+.2f", s.code_in_sigmas[i]);
    }
    std::snprintf(line, sizeof(line), "%-*s  %-4s  %11.4f  %9.4f  %-17s  %-17s  %s\n",
                  int(name_width), s.name.c_str(), s.kind.c_str(), s.rms_near_surface, s.rms_all,
                  FormatStats(s.accuracy).c_str(), FormatStats(s.completeness).c_str(), code.c_str());
    out << line;
  }
  if (shapes.size() > 1) {
    double near = 0, acc = 0;
    int n = 0;
    for (const auto& s : shapes) {
      if (!s.ok) continue;
      near += s.rms_near_surface, acc += s.accuracy.mean, ++n;
    }
    if (n > 0) {
      out << "mean over " << n << " shapes: rms_near " << Format("%.4f", near / n)
          << " m, accuracy mean " << Format("%.4f", acc / n) << " m\n";
    }
  }
  out << "(code in units of sigma_i, i.e. z_i / sigma_i; prior weight " << prior_weight << ")\n";
  return out.str();
}

EncodeSummary EncodeShapes(const ShapeModel& model, const EncodeOptions& options) {
  options.Check();
  model.Check();
  const std::vector<std::string> files = ListInputs(options.input);
  EncodeSummary summary;
  summary.prior_weight = options.prior_weight;
  const double near = options.near_surface_voxels * model.grid.voxel_size;
  std::set<std::string> used_names;
  for (const std::string& file : files) {
    EncodedShape shape;
    shape.file = file;
    shape.name = fs::path(file).stem().string();
    shape.kind = IsVdbFile(file) ? "sdf" : "cad";
    try {
      const ShapeInput input = LoadShapeInput(file, model, options.manifest_path);
      shape.name = input.name;
      shape.code = ProjectToManifold(model, input.sdf, options.prior_weight);
      const Eigen::VectorXf reconstruction = model.Shape(shape.code);
      double sum_near = 0.0, sum_all = 0.0;
      for (int64_t i = 0; i < model.NumVoxels(); ++i) {
        const double e = double(reconstruction[i]) - input.sdf[i];
        sum_all += e * e;
        if (std::abs(input.sdf[i]) < near) sum_near += e * e, ++shape.num_near_voxels;
      }
      shape.rms_all = std::sqrt(sum_all / double(model.NumVoxels()));
      shape.rms_near_surface =
          shape.num_near_voxels > 0 ? std::sqrt(sum_near / double(shape.num_near_voxels)) : 0.0;
      const Mesh mesh = ExtractSurface(model.grid, reconstruction);
      SAMP_CHECK(!mesh.Empty()) << "the reconstruction has no zero level set";
      const auto reconstructed_points =
          SampleSurface(mesh, options.num_distance_samples, options.seed);
      const auto original_points =
          input.kind == "cad" ? Subsample(input.original_points, options.num_distance_samples, options.seed)
                              : SampleSurface(input.original, options.num_distance_samples, options.seed + 1);
      shape.accuracy = NearestDistances(reconstructed_points, original_points);
      shape.completeness = NearestDistances(original_points, reconstructed_points);
      if (!options.output_folder.empty()) {
        std::string stem = shape.name;
        std::replace(stem.begin(), stem.end(), '/', '_');
        while (used_names.count(stem)) stem += "_";
        used_names.insert(stem);
        shape.mesh_path =
            (fs::path(options.output_folder) / (stem + "_reconstruction." + options.mesh_format)).string();
        ExportMesh(shape.mesh_path, mesh);
      }
      shape.code_in_sigmas = shape.code;
      for (int i = 0; i < shape.code.size(); ++i) {
        const double sigma = Sigma(model, i);
        shape.code_in_sigmas[i] = sigma > 0 ? shape.code[i] / sigma : 0.0;
      }
      shape.ok = true;
    } catch (const std::exception& e) {
      shape.error = e.what();
      LogWarning() << e.what();
    }
    summary.shapes.push_back(std::move(shape));
  }
  if (!options.output_folder.empty()) {
    std::ostringstream csv;
    csv << "name,kind,file,ok,rms_near_surface_m,num_near_voxels,rms_all_m,accuracy_mean_m,"
           "accuracy_p95_m,completeness_mean_m,completeness_p95_m,mesh";
    for (int i = 0; i < model.NumComponents(); ++i) csv << ",z" << i + 1;
    csv << "\n";
    for (const auto& s : summary.shapes) {
      csv << s.name << "," << s.kind << "," << s.file << "," << (s.ok ? 1 : 0) << ","
          << s.rms_near_surface << "," << s.num_near_voxels << "," << s.rms_all << ","
          << s.accuracy.mean << "," << s.accuracy.p95 << "," << s.completeness.mean << ","
          << s.completeness.p95 << "," << s.mesh_path;
      for (int i = 0; i < model.NumComponents(); ++i) csv << "," << (s.ok ? s.code[i] : 0.0);
      csv << "\n";
    }
    WriteTextFileAtomically((fs::path(options.output_folder) / "encode.csv").string(), csv.str());
  }
  return summary;
}

}  // namespace samp
