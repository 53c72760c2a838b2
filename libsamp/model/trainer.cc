#include "libsamp/model/trainer.h"

#include <tbb/parallel_for.h>
#include <sys/stat.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/core/json_fields.h"
#include "libsamp/core/json_text.h"
#include "libsamp/core/log.h"
#include "libsamp/core/object_pool.h"
#include "libsamp/core/progress.h"
#include "libsamp/core/util.h"
#include "libsamp/model/pca_option_table.h"
#include "libsamp/model/train_option_table.h"
#include "libsamp/scan/canonical.h"
#include "libsamp/scan/mesh_io.h"
#include "libsamp/scan/scan_option_table.h"
#include "libsamp/sdf/sdf_option_table.h"
#include "libsamp/sdf/vdb_io.h"

namespace samp {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

nlohmann::json Vector3Json(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

std::string VariantName(const std::string& name, const Eigen::Vector3d& f) {
  char suffix[64];
  std::snprintf(suffix, sizeof(suffix), "@%.2fx%.2fx%.2f", f.x(), f.y(), f.z());
  return name + suffix;
}

// Each usable job, then one stretched copy per size variant of it.
std::vector<TrainJob> AddSizeVariants(std::vector<TrainJob> jobs, const std::vector<Eigen::Vector3d>& variants) {
  const size_t originals = jobs.size();
  for (const Eigen::Vector3d& f : variants) {
    for (size_t i = 0; i < originals; ++i) {
      if (jobs[i].skip) continue;
      TrainJob copy = jobs[i];
      copy.name = VariantName(jobs[i].name, f);
      copy.size_factors = f;
      jobs.push_back(std::move(copy));
    }
  }
  return jobs;
}

std::vector<TrainJob> FindJobs(const TrainOptions& options, const Manifest* manifest) {
  const fs::path folder(options.cad_folder);
  std::error_code ec;
  SAMP_CHECK(fs::is_directory(folder, ec))
      << "CAD folder '" << options.cad_folder << "' is not a directory";
  std::vector<TrainJob> jobs;
  std::map<const ManifestEntry*, int> matched;
  for (const CadFile& file : ListCadFiles(options.cad_folder, manifest)) {
    TrainJob job;
    job.path = file.path;
    job.relative_path = file.relative_path;
    job.name = file.name;
    job.canonicalize = file.canonicalize;
    if (file.entry != nullptr) {
      ++matched[file.entry];
      job.skip = file.entry->skip;
      job.skip_reason = file.entry->skip_reason.empty() ? "no reason given" : file.entry->skip_reason;
    } else if (!options.preset.empty()) {
      job.canonicalize = CanonicalPreset(options.preset);
    }
    jobs.push_back(std::move(job));
  }
  SAMP_CHECK(!jobs.empty()) << "no mesh files (any format assimp reads) in CAD folder '"
                            << options.cad_folder << "'";
  if (manifest != nullptr) {
    for (const ManifestEntry& entry : manifest->entries) {
      if (matched.count(&entry) == 0) {
        LogWarning() << "manifest entry '" << entry.file << "' matches no mesh file in '"
                     << options.cad_folder << "'";
      }
    }
  }
  // Names must be unique (they name the training shapes and the SDF files):
  // clashing ones become their relative path without extension.
  std::map<std::string, int> count;
  for (const TrainJob& job : jobs) ++count[job.name];
  for (TrainJob& job : jobs) {
    if (count[job.name] > 1) {
      const fs::path relative(job.relative_path);
      job.name = (relative.parent_path() / relative.stem()).generic_string();
      std::replace(job.name.begin(), job.name.end(), '/', '_');
    }
  }
  return jobs;
}

// The per-model SDF file: one FloatGrid "sdf" with the model's provenance.
void SaveModelSdf(const std::string& path, const Sdf& sdf, const TrainJob& job,
                  const CanonicalizeResult& canonical) {
  VdbMetadata meta;
  meta["samp_file_type"] = "sdf";
  meta["samp_name"] = job.name;
  meta["samp_source_file"] = job.relative_path;
  meta["samp_scale"] = DumpJson(nlohmann::json(canonical.scale));
  meta["samp_up"] = canonical.up;
  meta["samp_forward"] = canonical.forward;
  meta["samp_size"] = DumpJson(Vector3Json(canonical.size));
  meta["samp_inside_fraction"] = DumpJson(nlohmann::json(sdf.summary.inside_fraction));
  WriteVdb(path, sdf.grid, {DenseGrid{"sdf", sdf.values}}, meta);
}

}  // namespace

void TrainOptions::Check() const {
  TrainOptionTable().Check(*this);
  grid.Check();
  scan.Check();
  sdf.Check();
  gate.Check();
  pca.Check();
}

std::string TrainOptions::ToJson() const { return DumpJson(OptionsToJson(*this)); }

TrainOptions TrainOptionsFromJson(const std::string& json, const std::string& source) {
  const nlohmann::json parsed = ParseJson(json, source);
  TrainOptions o;
  OptionsFromJson(JsonFields(parsed, source), &o);
  return o;
}

std::string TrainSummary::BriefReport() const {
  std::ostringstream out;
  size_t name_width = 5;
  for (const TrainedShape& s : shapes) name_width = std::max(name_width, s.name.size());
  char line[512];
  std::snprintf(line, sizeof(line), "%-*s  %-4s  %-22s  %7s  %5s  %7s  %s\n", int(name_width), "model",
                "used", "size l x h x w (m)", "inside", "fill", "time", "file / reason skipped");
  out << line;
  for (const TrainedShape& s : shapes) {
    const std::string size =
        s.size.isZero() ? "-"
                        : Fixed(s.size.x(), 2) + " x " + Fixed(s.size.y(), 2) +
                              " x " + Fixed(s.size.z(), 2);
    const std::string inside = s.inside_fraction > 0 ? Fixed(s.inside_fraction, 3) : "-";
    const std::string time = s.seconds > 0 ? Progress::FormatDuration(s.seconds) : "-";
    const std::string fill = s.quality.box_fill > 0 ? Fixed(s.quality.box_fill, 2) : "-";
    std::snprintf(line, sizeof(line), "%-*s  %-4s  %-22s  %7s  %5s  %7s  %s\n", int(name_width),
                  s.name.c_str(), s.used ? "yes" : "no", size.c_str(), inside.c_str(), fill.c_str(),
                  time.c_str(), s.used ? s.file.c_str() : s.reject_reason.c_str());
    out << line;
  }
  // The quality gate: skipped and borderline models with their figures.
  for (const TrainedShape& s : shapes) {
    if (!s.used && s.quality.box_fill > 0 && !s.quality.pass) {
      out << "skipped by the quality gate: " << s.name << " (" << s.quality.reason << ")\n";
    }
  }
  for (const TrainedShape& s : shapes) {
    if (s.used && s.quality.borderline) out << "borderline: " << s.name << " (" << s.quality.reason << ")\n";
  }
  out << "used " << num_used << " of " << shapes.size() << " models";
  if (eigenvalues.size() > 0) {
    out << "; PCA with R = " << eigenvalues.size() << "\n";
    out << "eigenvalues (variances, m^2):";
    for (int r = 0; r < eigenvalues.size(); ++r) out << " " << eigenvalues[r];
    out << "\nstandard deviations (m):     ";
    for (int r = 0; r < eigenvalues.size(); ++r) out << " " << std::sqrt(eigenvalues[r]);
    out << "\nexplained variance: " << Fixed(100.0 * explained_variance, 1) << " %";
  }
  out << "\ntotal time: " << Progress::FormatDuration(seconds) << "\n";
  return out.str();
}

CanonicalizeResult CanonicalCad(const std::string& path, const CanonicalizeOptions& options,
                                const Eigen::Vector3d& size_factors) {
  CanonicalizeResult canonical = Canonicalize(LoadMesh(path), options);
  if (size_factors != Eigen::Vector3d::Ones()) {
    // Canonical frame: x front (length), y down (height), z left (width),
    // origin at the bottom centre, which the stretch keeps in place.
    canonical.mesh.Transform(Eigen::Affine3d(size_factors.asDiagonal()));
    canonical.size = canonical.size.cwiseProduct(size_factors);
  }
  return canonical;
}

ScannedSdf ScanToSdf(const Mesh& canonical_mesh, const ScanOptions& scan, const GridSpec& grid,
                     const SdfOptions& sdf) {
  ScannedSdf result;
  result.sdf = ScanToSdf(canonical_mesh, scan, grid, sdf, &result.scan);
  return result;
}

Sdf ScanToSdf(const Mesh& canonical_mesh, const ScanOptions& scan, const GridSpec& grid, const SdfOptions& sdf,
              ScanResult* scan_result) {
  ScanMesh(canonical_mesh, scan, scan_result);
  SAMP_CHECK(scan_result->num_hits > 0) << "no scan ray hit the mesh";
  return ComputeSdf(canonical_mesh, *scan_result, grid, sdf, /*parallel=*/true);
}

std::vector<TrainJob> ListTrainJobs(const TrainOptions& options) {
  Manifest manifest;
  const bool has_manifest = !options.manifest_path.empty();
  if (has_manifest) manifest = LoadManifest(options.manifest_path);
  return AddSizeVariants(FindJobs(options, has_manifest ? &manifest : nullptr), options.size_variants);
}

namespace {

// Scan results kept between models so that their images (~128 MB each at the
// default scan) are reused, not allocated anew per model (core/object_pool.h;
// the fresh pages were 40 % of a model's time, docs/benchmarks.md,
// "samp.batch"). The pool holds as many results as models ever ran at once
// (num_threads of samp train, 1 per Dask task thread).
ObjectPool<ScanResult>& SharedScanBuffers() {
  static ObjectPool<ScanResult> pool;
  return pool;
}

}  // namespace

TrainedShape TrainJobSdf(const TrainJob& job, const TrainOptions& options, std::vector<float>* values) {
  TrainedShape shape;
  shape.name = job.name;
  shape.file = job.relative_path;
  shape.size_factors = job.size_factors;
  if (job.skip) {
    shape.reject_reason = "skipped by the manifest: " + job.skip_reason;
    return shape;
  }
  values->clear();
  const auto model_start = Clock::now();
  try {
    const CanonicalizeResult canonical = CanonicalCad(job.path, job.canonicalize, job.size_factors);
    for (const std::string& warning : canonical.warnings) {
      LogWarning() << job.relative_path << ": " << warning;
    }
    shape.scale = canonical.scale;
    shape.size = canonical.size;
    const ObjectPool<ScanResult>::Lease scan(&SharedScanBuffers());
    Sdf sdf = ScanToSdf(canonical.mesh, options.scan, options.grid, options.sdf, scan.get());
    shape.inside_fraction = sdf.summary.inside_fraction;
    SAMP_CHECK(sdf.summary.sign_ok)
        << "sign failed: inside fraction " << sdf.summary.inside_fraction
        << " below the minimum " << options.sdf.min_inside_fraction
        << " (open or inverted mesh, or not a car?)";
    shape.quality = CheckSdfQuality(sdf, canonical.mesh.Bounds(), options.gate);
    SAMP_CHECK(shape.quality.pass) << "SDF quality gate: " << shape.quality.reason;
    SAMP_CHECK(int64_t(sdf.values.size()) == options.grid.NumVoxels())
        << "SDF has " << sdf.values.size() << " values, expected "
        << options.grid.NumVoxels();
    if (!options.sdf_folder.empty()) {
      std::string file_name = job.name + ".vdb";
      SaveModelSdf((fs::path(options.sdf_folder) / file_name).string(), sdf, job, canonical);
    }
    *values = std::move(sdf.values);
    shape.used = true;
  } catch (const std::exception& e) {
    shape.reject_reason = e.what();
  } catch (...) {
    shape.reject_reason = "unknown error";
  }
  shape.seconds = SecondsSince(model_start);
  return shape;
}

namespace {

// Refuses outputs (the model file, the --sdf-dir files) that are inputs
// (a mesh of the CAD folder, the manifest), by resolved path or by device
// and inode (a hard link), before anything is computed.
void CheckOutputsAreNotInputs(const TrainOptions& options, const std::vector<TrainJob>& jobs) {
  auto resolved = [](const std::string& path) {
    std::error_code ec;
    const fs::path r = fs::weakly_canonical(fs::absolute(path), ec);
    return ec ? fs::absolute(path).lexically_normal().string() : r.string();
  };
  std::map<std::string, std::string> inputs;  // resolved path or "inode dev:ino" -> what
  auto add_input = [&](const std::string& path, const std::string& what) {
    inputs.emplace(resolved(path), what);
    struct stat st;
    if (::stat(path.c_str(), &st) == 0)
      inputs.emplace("inode " + std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino), what);
  };
  for (const TrainJob& job : jobs) add_input(job.path, "the input mesh " + job.path);
  if (!options.manifest_path.empty()) add_input(options.manifest_path, "the manifest " + options.manifest_path);
  auto check = [&](const std::string& what, const std::string& output) {
    auto it = inputs.find(resolved(output));
    struct stat st;
    if (it == inputs.end() && ::stat(output.c_str(), &st) == 0)
      it = inputs.find("inode " + std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino));
    SAMP_CHECK(it == inputs.end()) << "train: the " << what << " " << output << " is " << it->second
                                   << "; samp never writes over its inputs: give another output path";
  };
  check("model file", options.output_path);
  if (!options.sdf_folder.empty()) {
    for (const TrainJob& job : jobs) check("SDF file", (fs::path(options.sdf_folder) / (job.name + ".vdb")).string());
  }
}

}  // namespace

TrainSummary TrainShapeModel(const TrainOptions& options) {
  options.Check();
  const auto start = Clock::now();
  const std::vector<TrainJob> jobs = ListTrainJobs(options);
  CheckOutputsAreNotInputs(options, jobs);
  const int num_jobs = int(jobs.size());
  LogInfo() << "training a shape model from " << num_jobs << " mesh files in "
            << options.cad_folder << " on the grid " << options.grid.ToString();

  TrainSummary summary;
  summary.shapes.resize(num_jobs);
  std::vector<std::vector<float>> sdf_values(num_jobs);
  for (int i = 0; i < num_jobs; ++i) {
    summary.shapes[i].name = jobs[i].name;
    summary.shapes[i].file = jobs[i].relative_path;
    summary.shapes[i].size_factors = jobs[i].size_factors;
    if (jobs[i].skip) {
      summary.shapes[i].reject_reason = "skipped by the manifest: " + jobs[i].skip_reason;
      LogWarning() << "skipping " << jobs[i].relative_path << ": "
                   << summary.shapes[i].reject_reason;
    }
  }

  tbb::task_arena arena(options.num_threads > 0 ? options.num_threads
                                                : int(tbb::task_arena::automatic));
  Progress progress("scanning", num_jobs, options.show_progress);
  arena.execute([&] {
    tbb::parallel_for(0, num_jobs, 1, [&](int i) {
      const TrainJob& job = jobs[i];
      TrainedShape& shape = summary.shapes[i];
      if (job.skip) {
        progress.Tick();
        return;
      }
      shape = TrainJobSdf(job, options, &sdf_values[i]);
      if (!shape.used) LogWarning() << "skipping " << job.relative_path << ": " << shape.reject_reason;
      progress.Tick();
    });
  });
  progress.Finish();

  std::vector<int> used;
  for (int i = 0; i < num_jobs; ++i) {
    if (summary.shapes[i].used) used.push_back(i);
  }
  summary.num_used = int(used.size());
  const int needed = options.pca.num_components + 1;
  if (summary.num_used < needed) {
    summary.seconds = SecondsSince(start);
    LogInfo() << "\n" << summary.BriefReport();
    SAMP_THROW() << "only " << summary.num_used << " of " << num_jobs
                 << " models are usable; a model with R = " << options.pca.num_components
                 << " components needs at least " << needed
                 << " (see the 'skipping' lines above for the reasons)";
  }

  // PCA over the used models' SDFs (one column each, in file order).
  const int64_t dim = options.grid.NumVoxels();
  Eigen::MatrixXf samples(dim, summary.num_used);
  for (int c = 0; c < summary.num_used; ++c) {
    samples.col(c) = Eigen::Map<const Eigen::VectorXf>(sdf_values[used[c]].data(), dim);
    std::vector<float>().swap(sdf_values[used[c]]);
  }
  PcaResult pca;
  arena.execute([&] { pca = ComputePca(samples, options.pca); });

  ShapeModel model;
  model.grid = options.grid;
  model.mean = std::move(pca.mean);
  model.components = std::move(pca.components);
  model.eigenvalues = pca.eigenvalues;
  model.total_variance = pca.total_variance;
  for (int i : used) model.training_shapes.push_back(summary.shapes[i].name);
  model.options_json = options.ToJson();
  model.Save(options.output_path);

  summary.eigenvalues = pca.eigenvalues;
  summary.explained_variance =
      pca.total_variance > 0 ? pca.eigenvalues.sum() / pca.total_variance : 0.0;
  summary.seconds = SecondsSince(start);
  LogInfo() << "wrote " << options.output_path;
  return summary;
}

}  // namespace samp
