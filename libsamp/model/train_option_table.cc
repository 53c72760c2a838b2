#include "libsamp/model/train_option_table.h"

#include "libsamp/model/pca_option_table.h"
#include "libsamp/scan/canonical.h"
#include "libsamp/scan/scan_option_table.h"
#include "libsamp/sdf/sdf_option_table.h"

namespace samp {

namespace {

OptionTable<TrainOptions> MakeTrainTable() {
  using O = TrainOptions;
  OptionTable<O> t("TrainOptions");
  // The help is samp train's.
  t.Add("cad_folder", &O::cad_folder, "Folder searched recursively for mesh files (other files are ignored)")
      .Positional("CAD_FOLDER")
      .Required()
      .ExistingDirectory();
  t.Add("output_path", &O::output_path, "The model file to write (.vdb, written atomically; docs/model_format.md)")
      .Short('o')
      .Flag("output")
      .Required()
      .NotInJson();
  t.Add("manifest", &O::manifest_path,
        "JSON manifest: per file name, scale or target length, up/forward axes, skip (docs/canonical_frame.md); "
        "without it axes are auto-detected")
      .ExistingFile();
  t.Add("preset", &O::preset,
        "Canonicalisation of the files no manifest entry lists: shapenet (ShapeNetCore v2: +y up, front -z, unit "
        "diagonal -> 4.49 m) or apollocar3d (car_models_json: metres, y down, front +z); docs/canonical_frame.md")
      .ChoicesOrEmpty(CanonicalPresetNames());
  t.Add("sdf_folder", &O::sdf_folder, "Also write each model's SDF as <name>.vdb into this folder")
      .Flag("sdf-dir")
      .NotInJson();
  // The model file stores the whole grid (TrainOptions::ToJson). The voxel
  // size and the box's three edges each set the car grid
  // (GridSpec::Car) and keep the other three as they are.
  t.AddComputed<double>(
       "voxel_size", [](const O& o) { return o.grid.voxel_size; },
       [](O* o, double voxel_size) {
         const Eigen::Vector3d size = o->grid.Size();
         o->grid = GridSpec::Car(size.x(), size.y(), size.z(), voxel_size);
       },
       "Voxel size in metres of the car grid (by default a 6.0 x 2.8 x 2.8 m box around the canonical car)")
      .Flag("voxel")
      .Positive();
  const char* axis_names[3] = {"grid_length", "grid_height", "grid_width"};
  const std::string axis_help[3] = {
      std::string("Length (x) of the car grid, m, centred on the car: a shape longer than the box is cut off ") +
          "(docs/training.md, Grid)",
      "Height (y) of the car grid, m: from 0.5 m below the car's bottom up to height - 0.5 m above it",
      "Width (z) of the car grid, m, centred on the car"};
  for (int axis = 0; axis < 3; ++axis) {
    t.AddComputed<double>(
         axis_names[axis], [axis](const O& o) { return o.grid.Size()[axis]; },
         [axis](O* o, double edge) {
           Eigen::Vector3d size = o->grid.Size();
           size[axis] = edge;
           o->grid = GridSpec::Car(size.x(), size.y(), size.z(), o->grid.voxel_size);
         },
         axis_help[axis])
        .Positive();
  }
  // The model file stores scan.width and scan.height.
  t.AddComputed<int>(
       "resolution", [](const O& o) { return o.scan.width; },
       [](O* o, int pixels) { o->scan.width = o->scan.height = pixels; },
       "Width and height in pixels (rays) of each scan view (scan.width, scan.height)")
      .Positive();
  t.AddList("size_variants", &O::size_variants,
            "Also train on each car stretched by these factors of length, height and width (repeatable: one copy "
            "of every car per occurrence; docs/training.md, Size variants)")
      .Flag("size-variant")
      .AtLeast(0.5)
      .AtMost(2.0)
      .DefaultWhenAbsent();  // model files written before size variants existed: none were used
  t.Add("num_threads", &O::num_threads, "Worker threads (0 = all cores)").Flag("threads").NonNegative().NotInJson();
  t.Add("show_progress", &O::show_progress, "progress bars on the terminal (samp train: unless --quiet)")
      .Internal()
      .NotInJson();
  return t;
}

// The car grid as the model file stores it: origin, voxel size, dims.
void GridFields(OptionsJson& io, GridSpec& grid) {
  std::vector<double> origin = {grid.origin.x(), grid.origin.y(), grid.origin.z()};
  std::vector<int> dims = {grid.dims.x(), grid.dims.y(), grid.dims.z()};
  io("origin", origin);
  io("voxel_size", grid.voxel_size);
  io("dims", dims);
  if (io.writing()) return;
  SAMP_CHECK(origin.size() == 3 && dims.size() == 3) << "grid: 'origin' and 'dims' must have 3 entries each";
  grid.origin = Eigen::Vector3d(origin[0], origin[1], origin[2]);
  grid.dims = Eigen::Vector3i(dims[0], dims[1], dims[2]);
}

}  // namespace

const OptionTable<TrainOptions>& TrainOptionTable() {
  static const OptionTable<TrainOptions> table = MakeTrainTable();
  return table;
}

void OptionFields(OptionsJson& io, TrainOptions& o) {
  TrainOptionTable().Json(io, o);
  io.NestedWith("grid", [&o](OptionsJson& grid_io) { GridFields(grid_io, o.grid); });
  io.Nested("scan", o.scan);
  io.Nested("sdf", o.sdf);
  io.Nested("gate", o.gate);
  io.Nested("pca", o.pca);
}

}  // namespace samp
