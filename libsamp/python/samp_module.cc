// The native half of the Python package `samp` (libsamp/python/samp/): the
// C++ module `_samp`. It wraps library calls one to one and keeps no state of
// its own; the Python package builds the user-facing API on top of it
// (docs/python.md).
//
// - Options cross the boundary as the JSON of the library's own field tables
//   (OptionFields in pipeline/fit_config.h, TrainOptions::ToJson): one native
//   object per options struct with to_json()/from_json()/check(), so every
//   field of the struct is reachable by its config.json name and a wrong type
//   or an invalid value is the library's own samp::Error.
// - samp::Error becomes the Python exception samp.Error with the same message.
// - Every call that does native work releases the GIL.
// - Dense grids are NumPy arrays of shape (nx, ny, nz) in Fortran order, so
//   a[i, j, k] is the value at GridSpec::Position(i, j, k) and the memory is
//   the library's x-fastest layout.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <tbb/task_arena.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "libsamp/core/json_text.h"
#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/core/json_fields.h"
#include "libsamp/core/ply_io.h"
#include "libsamp/data/kitti_tracking.h"
#include "libsamp/data/sequence.h"
#include "libsamp/model/gram.h"
#include "libsamp/model/manifold_projection.h"
#include "libsamp/model/shape_model.h"
#include "libsamp/model/trainer.h"
#include "libsamp/pipeline/fit_config.h"
#include "libsamp/pipeline/fit_output.h"
#include "libsamp/pipeline/run_fit.h"
#include "libsamp/scan/canonical.h"
#include "libsamp/sdf/surface.h"
#include "libsamp/viz/detector_noise_plot.h"

namespace py = pybind11;
namespace fs = std::filesystem;

namespace samp::python {
namespace {

// Runs f() with the GIL released and returns its result: samp's C++ work
// touches no Python object, so other Python threads (and Dask's) run meanwhile.
template <typename F>
auto WithoutGil(F&& f) {
  py::gil_scoped_release release;
  return f();
}

// ---------------------------------------------------------------- options

// An options struct whose fields are listed by OptionFields (core/json_fields.h).
template <typename S>
struct FieldTableCodec {
  static std::string ToJson(const S& o) { return DumpJson(OptionsToJson(o, JsonDefaults::kWrite)); }
  static S FromJson(const std::string& text, const std::string& source) {
    const nlohmann::json j = ParseJson(text, source);
    const JsonFields fields(j, source);
    S o;
    OptionsFromJson(fields, &o);
    return o;
  }
};

// TrainOptions: the model file's reader and writer (TrainOptions::ToJson,
// TrainOptionsFromJson), plus the fields the model file does not store
// (output, sdf_folder, num_threads, show_progress).
struct TrainCodec {
  static std::string ToJson(const TrainOptions& o) {
    nlohmann::json j = nlohmann::json::parse(o.ToJson());
    j["output"] = o.output_path;
    j["sdf_folder"] = o.sdf_folder;
    j["num_threads"] = o.num_threads;
    j["show_progress"] = o.show_progress;
    return DumpJson(j);
  }
  static TrainOptions FromJson(const std::string& text, const std::string& source) {
    nlohmann::json j = ParseJson(text, source);
    const JsonFields fields(j, source);
    const int num_threads = fields.Get<int>("num_threads");
    const bool show_progress = fields.Get<bool>("show_progress");
    const std::string output = fields.Get<std::string>("output");
    const std::string sdf_folder = fields.Get<std::string>("sdf_folder");
    for (const char* key : {"num_threads", "show_progress", "output", "sdf_folder"}) j.erase(key);
    TrainOptions o = TrainOptionsFromJson(DumpJson(j), source);
    o.output_path = output;
    o.sdf_folder = sdf_folder;
    o.num_threads = num_threads;
    o.show_progress = show_progress;
    return o;
  }
};

template <typename S, typename Codec>
void BindOptions(py::module_& m, const char* name) {
  py::class_<S>(m, name)
      .def(py::init<>())
      .def("to_json", [](const S& o) { return Codec::ToJson(o); },
           "Every field as JSON text (the names of config.json / the model file's options).")
      .def("from_json",
           [name](S& o, const std::string& text) { o = Codec::FromJson(text, name); },
           "Replaces every field from JSON text; every key is required; a wrong type raises samp.Error.")
      .def("check", [](const S& o) { o.Check(); }, "The library's Check(): raises samp.Error naming the field.");
}

// ---------------------------------------------------------------- arrays

// (nx, ny, nz) Fortran-order array of a dense grid (D values, x-fastest).
py::array_t<float> GridArray(const GridSpec& grid, const float* values) {
  py::array_t<float, py::array::f_style> a(
      std::vector<py::ssize_t>{grid.dims.x(), grid.dims.y(), grid.dims.z()});
  std::copy(values, values + grid.NumVoxels(), a.mutable_data());
  return a;
}

// D values of a grid given as an (nx, ny, nz) array or D flat values.
std::vector<float> GridValues(const GridSpec& grid, const py::array& array, const char* what) {
  const int64_t dim = grid.NumVoxels();
  if (array.ndim() == 3) {
    SAMP_CHECK(array.shape(0) == grid.dims.x() && array.shape(1) == grid.dims.y() &&
               array.shape(2) == grid.dims.z())
        << what << ": shape (" << array.shape(0) << ", " << array.shape(1) << ", " << array.shape(2)
        << ") is not the grid's (" << grid.dims.x() << ", " << grid.dims.y() << ", " << grid.dims.z() << ")";
  } else {
    SAMP_CHECK(array.ndim() == 1 && array.shape(0) == dim)
        << what << ": expected an array of shape (" << grid.dims.x() << ", " << grid.dims.y() << ", "
        << grid.dims.z() << ") or " << dim << " flat values (x fastest)";
  }
  // Fortran order of a 3D array is the library's x-fastest order.
  const auto f = py::array_t<float, py::array::f_style | py::array::forcecast>::ensure(array);
  SAMP_CHECK(f) << what << ": not convertible to float32";
  return std::vector<float>(f.data(), f.data() + dim);
}

py::dict GridDict(const GridSpec& grid) {
  py::dict d;
  d["origin"] = Eigen::Vector3d(grid.origin);
  d["voxel_size"] = grid.voxel_size;
  d["dims"] = Eigen::Vector3i(grid.dims);
  return d;
}

py::tuple MeshTuple(const Mesh& mesh) {
  py::array_t<float> vertices({py::ssize_t(mesh.vertices.size()), py::ssize_t(3)});
  py::array_t<int32_t> faces({py::ssize_t(mesh.triangles.size()), py::ssize_t(3)});
  auto v = vertices.mutable_unchecked<2>();
  for (size_t i = 0; i < mesh.vertices.size(); ++i)
    for (int c = 0; c < 3; ++c) v(i, c) = mesh.vertices[i][c];
  auto f = faces.mutable_unchecked<2>();
  for (size_t i = 0; i < mesh.triangles.size(); ++i)
    for (int c = 0; c < 3; ++c) f(i, c) = mesh.triangles[i][c];
  return py::make_tuple(vertices, faces);
}

// ---------------------------------------------------------------- fit output

// Copies a folder written by RunFit (`from`) to `to` as `samp fit --out TO`
// would have written it: every file as it is, config.json rewritten by its
// writer with output_dir = `to`. `to` is replaced as a whole (StagedFolder)
// and must be new, empty or an earlier samp fit output, as RunFit requires.
void WriteFitOutput(const std::string& from, const std::string& to) {
  std::error_code ec;
  const fs::file_status status = fs::status(to, ec);
  if (fs::exists(status)) {
    SAMP_CHECK(fs::is_directory(status)) << "output folder " << to << " exists and is not a folder";
    SAMP_CHECK(fs::is_empty(to, ec) ||
               (fs::is_regular_file(fs::path(to) / "tracks.json", ec) &&
                fs::is_regular_file(fs::path(to) / "config.json", ec)))
        << "output folder " << to << " is not empty and not the output of a samp fit (it has no "
        << "tracks.json and config.json); give a new or empty folder";
  }
  FitConfig config = ReadFitConfig((fs::path(from) / "config.json").string());
  config.options.output_dir = to;
  StagedFolder staged(to);
  fs::copy(from, staged.path(), fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  WriteFitConfig((fs::path(staged.path()) / "config.json").string(), config);
  staged.Commit();
}

py::dict SequenceResultDict(const SequenceFitResult& r) {
  py::dict d;
  d["directory"] = r.directory;
  d["name"] = r.name;
  d["ok"] = r.ok;
  d["error"] = r.error;
  d["num_tracks"] = r.num_tracks;
  d["num_fitted"] = r.num_fitted;
  d["num_at_grid_limit"] = r.num_at_grid_limit;
  d["track_failures"] = r.track_failures;
  d["input"] = r.input.BriefReport();
  d["tracker"] = r.ok ? r.input.tracking.BriefReport() : std::string();
  d["seconds"] = r.seconds;
  d["seconds_frames"] = r.input.seconds_frames;
  d["seconds_tracking"] = r.input.seconds_tracking;
  d["seconds_fit"] = r.seconds_fit;
  d["seconds_output"] = r.seconds_output;
  return d;
}

py::dict SummaryDict(const RunFitSummary& s) {
  py::dict d;
  py::list sequences;
  for (const auto& q : s.sequences) sequences.append(SequenceResultDict(q));
  d["sequences"] = sequences;
  d["num_sequences_failed"] = s.num_sequences_failed;
  d["num_tracks_fitted"] = s.num_tracks_fitted;
  d["num_tracks_failed"] = s.num_tracks_failed;
  d["failure"] = s.failure;
  d["replaced_previous_output"] = s.replaced_previous_output;
  // The detector model the run used (its file's format: DetectorNoiseModel::ToJson), None without one.
  d["detector_model"] = s.detector_model_used ? py::module_::import("json").attr("loads")(s.detector_model.ToJson())
                                              : py::object(py::none());
  d["seconds_calibration"] = s.seconds_calibration;
  d["seconds"] = s.seconds;
  d["report"] = s.BriefReport();
  return d;
}

// ---------------------------------------------------------------- SDF of one mesh

py::dict SdfOfMesh(const std::string& path, const TrainOptions& options) {
  options.scan.Check();
  options.sdf.Check();
  options.grid.Check();
  CanonicalizeResult canonical;
  ScannedSdf scanned;
  {
    py::gil_scoped_release release;
    // As the trainer treats the file: its manifest entry (matched by the path
    // relative to options.cad_folder, else its name), else the manifest's
    // defaults or the preset.
    CanonicalizeOptions canonicalize =
        options.preset.empty() ? CanonicalizeOptions() : CanonicalPreset(options.preset);
    if (!options.manifest_path.empty()) {
      const Manifest manifest = LoadManifest(options.manifest_path);
      std::string relative = fs::path(path).filename().string();
      if (!options.cad_folder.empty()) {
        const fs::path r = fs::path(path).lexically_normal().lexically_relative(fs::path(options.cad_folder).lexically_normal());
        if (!r.empty() && *r.begin() != "..") relative = r.generic_string();
      }
      const ManifestEntry* entry = manifest.Find(relative);
      if (entry != nullptr) {
        SAMP_CHECK(!entry->skip) << path << ": skipped by the manifest " << options.manifest_path << ": "
                                 << entry->skip_reason;
        canonicalize = entry->canonicalize;
      } else if (options.preset.empty()) {
        canonicalize = manifest.defaults;
      }
    }
    canonical = CanonicalCad(path, canonicalize);
    scanned = ScanToSdf(canonical.mesh, options.scan, options.grid, options.sdf);
  }
  const Sdf& sdf = scanned.sdf;
  py::dict d;
  d["values"] = GridArray(sdf.grid, sdf.values.data());
  d["grid"] = GridDict(sdf.grid);
  d["inside_fraction"] = sdf.summary.inside_fraction;
  d["sign_ok"] = sdf.summary.sign_ok;
  d["report"] = sdf.summary.BriefReport();
  d["scale"] = canonical.scale;
  d["size"] = Eigen::Vector3d(canonical.size);
  d["up"] = canonical.up;
  d["forward"] = canonical.forward;
  d["warnings"] = canonical.warnings;
  return d;
}

}  // namespace
}  // namespace samp::python

using namespace samp;
using namespace samp::python;

PYBIND11_MODULE(_samp, m) {
  m.doc() = "samp's native module (use the package `samp`).";
  static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      error(e.what());
    } catch (const fs::filesystem_error& e) {
      error(e.what());
    }
  });

  BindOptions<RunFitOptions, FieldTableCodec<RunFitOptions>>(m, "RunFitOptions");
  BindOptions<FitOptions, FieldTableCodec<FitOptions>>(m, "FitOptions");
  BindOptions<SequenceOptions, FieldTableCodec<SequenceOptions>>(m, "SequenceOptions");
  BindOptions<TrainOptions, TrainCodec>(m, "TrainOptions");

  py::class_<ShapeModel, std::shared_ptr<ShapeModel>>(m, "ShapeModel")
      .def_static(
          "load",
          [](const std::string& path) {
            py::gil_scoped_release release;
            return std::make_shared<ShapeModel>(ShapeModel::Load(path));
          },
          py::arg("path"))
      .def_property_readonly("num_components", &ShapeModel::NumComponents)
      .def_property_readonly("num_voxels", &ShapeModel::NumVoxels)
      .def_property_readonly("grid", [](const ShapeModel& s) { return GridDict(s.grid); })
      .def_property_readonly("mean", [](const ShapeModel& s) { return GridArray(s.grid, s.mean.data()); })
      .def_property_readonly("components",
                             [](const ShapeModel& s) {
                               // (nx, ny, nz, R), Fortran order: the D x R column-major matrix.
                               py::array_t<float, py::array::f_style> a(
                                   {py::ssize_t(s.grid.dims.x()), py::ssize_t(s.grid.dims.y()),
                                    py::ssize_t(s.grid.dims.z()), py::ssize_t(s.NumComponents())});
                               std::copy(s.components.data(), s.components.data() + s.components.size(),
                                         a.mutable_data());
                               return a;
                             })
      .def_property_readonly("eigenvalues", [](const ShapeModel& s) { return Eigen::VectorXd(s.eigenvalues); })
      .def_property_readonly("total_variance", [](const ShapeModel& s) { return s.total_variance; })
      .def_property_readonly("training_shapes", [](const ShapeModel& s) { return s.training_shapes; })
      .def_property_readonly("options_json", [](const ShapeModel& s) { return s.options_json; })
      .def("sdf",
           [](const ShapeModel& s, const Eigen::VectorXd& z) {
             SAMP_CHECK(z.size() == s.NumComponents())
                 << "ShapeModel.sdf: the code has " << z.size() << " values, the model "
                 << s.NumComponents() << " components";
             const Eigen::VectorXf values = WithoutGil([&] { return s.Shape(z); });
             return GridArray(s.grid, values.data());
           },
           py::arg("z"))
      .def("mesh",
           [](const ShapeModel& s, const Eigen::VectorXd& z, double isovalue) {
             SAMP_CHECK(z.size() == s.NumComponents())
                 << "ShapeModel.mesh: the code has " << z.size() << " values, the model "
                 << s.NumComponents() << " components";
             return MeshTuple(WithoutGil([&] { return ExtractSurface(s.grid, s.Shape(z), isovalue); }));
           },
           py::arg("z"), py::arg("isovalue") = 0.0)
      .def("encode",
           [](const ShapeModel& s, const py::array& sdf, double prior_weight) {
             const std::vector<float> values = GridValues(s.grid, sdf, "ShapeModel.encode");
             py::gil_scoped_release release;
             return ProjectToManifold(s, values, prior_weight);
           },
           py::arg("sdf"), py::arg("prior_weight") = 0.0);

  m.def(
      "run_fit",
      [](RunFitOptions options) {
        // OUT/detector_model.png as `samp fit` draws it.
        options.draw_detector_model = [](const std::string& path, const DetectorNoiseModel& model) {
          WriteDetectorNoisePlot(path, model);
        };
        return SummaryDict(WithoutGil([&] { return RunFit(options); }));
      },
      py::arg("options"), "RunFit (pipeline/run_fit.h): `samp fit` as one call; returns its summary.");
  m.def(
      "write_fit_output",
      [](const std::string& from, const std::string& to) {
        py::gil_scoped_release release;
        WriteFitOutput(from, to);
      },
      py::arg("source"), py::arg("output_dir"));
  m.def(
      "kitti_tracking_sequence_folders",
      [](const std::string& root, const std::string& sequences) {
        return KittiTrackingSequenceFolders(root, sequences);
      },
      py::arg("root"), py::arg("sequences") = "all",
      "KittiTrackingSequenceFolders (data/kitti_tracking.h): ROOT/image_02/<seq> of 'all' or a list.");
  m.def(
      "kitti_stereo_sequences",
      [](const std::string& root, const std::string& sequences) { return KittiStereoSequences(root, sequences); },
      py::arg("root"), py::arg("sequences") = "all",
      "KittiStereoSequences (data/sequence.h): ROOT/calib_cam_to_cam/<seq>.txt of 'all' or a list.");
  m.def(
      "parse_frame_range",
      [](const std::string& range) {
        SequenceOptions o;
        ParseFrameRange(range, &o);
        return py::make_tuple(o.first_frame, o.last_frame);
      },
      py::arg("range"), "ParseFrameRange (data/sequence.h): 'FIRST-LAST' -> (first, last).");
  m.def(
      "sequence_output_name", [](const std::string& directory) { return SequenceOutputName(directory); },
      py::arg("directory"));
  m.def(
      "train",
      [](const TrainOptions& options) {
        const TrainSummary summary = WithoutGil([&] { return TrainShapeModel(options); });
        py::dict d;
        d["num_used"] = summary.num_used;
        d["eigenvalues"] = summary.eigenvalues;
        d["explained_variance"] = summary.explained_variance;
        d["seconds"] = summary.seconds;
        d["report"] = summary.BriefReport();
        py::list shapes;
        for (const TrainedShape& s : summary.shapes) {
          py::dict t;
          t["name"] = s.name;
          t["file"] = s.file;
          t["used"] = s.used;
          t["reject_reason"] = s.reject_reason;
          t["seconds"] = s.seconds;
          shapes.append(t);
        }
        d["shapes"] = shapes;
        return d;
      },
      py::arg("options"), "TrainShapeModel (model/trainer.h): `samp train` as one call.");
  py::class_<TrainJob>(m, "TrainJob")
      .def_readonly("path", &TrainJob::path)
      .def_readonly("relative_path", &TrainJob::relative_path)
      .def_readonly("name", &TrainJob::name)
      .def_readonly("skip", &TrainJob::skip)
      .def_readonly("skip_reason", &TrainJob::skip_reason);
  m.def(
      "list_train_jobs",
      [](const TrainOptions& options) {
        options.Check();
        py::gil_scoped_release release;
        return ListTrainJobs(options);
      },
      py::arg("options"), "ListTrainJobs (model/trainer.h): the models TrainShapeModel trains on, in order.");
  m.def(
      "train_job_sdf",
      [](const TrainJob& job, const TrainOptions& options) {
        std::vector<float> values;
        TrainedShape shape;
        {
          py::gil_scoped_release release;
          // The TBB threads of the SDF: options.num_threads (0 = all cores), as in samp train.
          tbb::task_arena arena(options.num_threads > 0 ? options.num_threads
                                                        : int(tbb::task_arena::automatic));
          arena.execute([&] { shape = TrainJobSdf(job, options, &values); });
        }
        py::dict d;
        d["name"] = shape.name;
        d["file"] = shape.file;
        d["used"] = shape.used;
        d["reject_reason"] = shape.reject_reason;
        d["scale"] = shape.scale;
        d["size"] = Eigen::Vector3d(shape.size);
        d["inside_fraction"] = shape.inside_fraction;
        d["seconds"] = shape.seconds;
        py::array_t<float> a(py::ssize_t(values.size()));
        std::copy(values.begin(), values.end(), a.mutable_data());
        d["values"] = a;  // D values, x fastest (empty when not used)
        return d;
      },
      py::arg("job"), py::arg("options"), "TrainJobSdf (model/trainer.h): one model's SDF as training computes it.");
  m.def(
      "save_model",
      [](const TrainOptions& options, const py::array& mean_array, const py::array& components_array,
         const Eigen::VectorXd& eigenvalues, double total_variance, const std::vector<std::string>& names) {
        options.Check();
        const int64_t dim = options.grid.NumVoxels();
        const auto mean = py::array_t<float, py::array::f_style | py::array::forcecast>::ensure(mean_array);
        const auto components =
            py::array_t<float, py::array::f_style | py::array::forcecast>::ensure(components_array);
        SAMP_CHECK(mean && mean.size() == dim) << "save_model: the mean must have " << dim << " values";
        SAMP_CHECK(components && components.ndim() == 2 && components.shape(0) == dim &&
                   components.shape(1) == eigenvalues.size())
            << "save_model: components must be " << dim << " x " << eigenvalues.size();
        ShapeModel model;
        model.grid = options.grid;
        model.mean = Eigen::Map<const Eigen::VectorXf>(mean.data(), dim);
        model.components = Eigen::Map<const Eigen::MatrixXf>(components.data(), dim, components.shape(1));
        model.eigenvalues = eigenvalues;
        model.total_variance = total_variance;
        model.training_shapes = names;
        model.options_json = options.ToJson();
        py::gil_scoped_release release;
        model.Check();
        model.Save(options.output_path);
      },
      py::arg("options"), py::arg("mean"), py::arg("components"), py::arg("eigenvalues"),
      py::arg("total_variance"), py::arg("names"),
      "A model file (ShapeModel::Save) on options.grid with the trainer's options in its metadata.");
  // The PCA's two products (model/gram.h) on blocks of grids, for a PCA whose
  // grids are spread over processes (samp.batch train): the same float
  // kernels, so the same sums as model/pca.cc.
  m.def(
      "centred_gram",
      [](const py::array& x_array, const py::array& mean_array) {
        const auto x = py::array_t<float, py::array::f_style | py::array::forcecast>::ensure(x_array);
        const auto mean = py::array_t<float, py::array::f_style | py::array::forcecast>::ensure(mean_array);
        SAMP_CHECK(x && x.ndim() == 2 && mean && mean.size() == x.shape(0))
            << "centred_gram: x must be D x N and mean D values";
        const int64_t dim = x.shape(0), n = x.shape(1);
        py::array_t<double, py::array::f_style> gram(std::vector<py::ssize_t>{n, n});
        double* out = gram.mutable_data();
        py::gil_scoped_release release;
        CentredGram(x.data(), dim, n, mean.data(), out, BestGramKernel());
        return gram;
      },
      py::arg("x"), py::arg("mean"), "CentredGram (model/gram.h): Xc^T Xc of x (D x N float32) centred by mean.");
  m.def(
      "centred_product",
      [](const py::array& x_array, const py::array& mean_array, const py::array& p_array) {
        const auto x = py::array_t<float, py::array::f_style | py::array::forcecast>::ensure(x_array);
        const auto mean = py::array_t<float, py::array::f_style | py::array::forcecast>::ensure(mean_array);
        const auto p = py::array_t<double, py::array::f_style | py::array::forcecast>::ensure(p_array);
        SAMP_CHECK(x && x.ndim() == 2 && mean && mean.size() == x.shape(0) && p && p.ndim() == 2 &&
                   p.shape(0) == x.shape(1))
            << "centred_product: x must be D x N, mean D values and p N x C";
        const int64_t dim = x.shape(0), n = x.shape(1), c = p.shape(1);
        py::array_t<double, py::array::f_style> product(std::vector<py::ssize_t>{dim, c});
        double* out = product.mutable_data();
        py::gil_scoped_release release;
        CentredProduct(x.data(), dim, n, mean.data(), p.data(), c, out, BestGramKernel());
        return product;
      },
      py::arg("x"), py::arg("mean"), py::arg("p"), "CentredProduct (model/gram.h): Xc P.");
  m.def("sdf_of_mesh", &SdfOfMesh, py::arg("path"), py::arg("options"),
        "CanonicalCad + ScanToSdf (model/trainer.h): the SDF of one CAD file as training computes it.");
}
