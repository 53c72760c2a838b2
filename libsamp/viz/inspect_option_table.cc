#include "libsamp/viz/inspect_option_table.h"

namespace samp {

namespace {

const std::vector<std::string> kMeshFormats = {"ply", "obj", "glb"};

OptionTable<EigenShapeMeshOptions> MakeEigenShapeMeshTable() {
  using O = EigenShapeMeshOptions;
  OptionTable<O> t("EigenShapeMeshOptions");
  t.Add("output_folder", &O::output_folder, "the meshes' folder, created if missing (samp inspect --meshes)")
      .Internal()
      .Rule("given", [](const O& o) { return !o.output_folder.empty(); });
  // The help is samp inspect's.
  t.AddList("ks", &O::ks, "Multiples of sigma for --meshes, comma-separated")
      .Flag("k")
      .Separator(',')
      .Rule("a non-empty list", [](const O& o) { return !o.ks.empty(); });
  t.Add("format", &O::format, "Mesh format for --meshes and --encode").Choices(kMeshFormats);
  t.Add("max_components", &O::max_components, "Components for --meshes and the eigen-shape picture (0 = all R)")
      .Flag("components")
      .NonNegative();
  return t;
}

OptionTable<EncodeOptions> MakeEncodeTable() {
  using O = EncodeOptions;
  OptionTable<O> t("EncodeOptions");
  t.Add("input", &O::input, "a CAD file, a per-model SDF .vdb or a folder of them (samp inspect --encode)")
      .Internal()
      .Rule("given", [](const O& o) { return !o.input.empty(); });
  t.Add("output_folder", &O::output_folder, "reconstructed meshes and encode.csv (empty: none; samp inspect --out)")
      .Internal();
  t.Add("manifest_path", &O::manifest_path, "canonicalisation of CAD files (samp inspect --manifest)").Internal();
  // The help is samp inspect's.
  t.Add("prior_weight", &O::prior_weight,
        "Weight lambda of the Gaussian prior in the projection: z_i = w_i^T(x - mu) / (1 + lambda / sigma_i^2); "
        "0 = least squares")
      .NonNegative();
  t.Add("near_surface_voxels", &O::near_surface_voxels, "RMS SDF error over voxels with |sdf| below this many voxels")
      .Flag("near")
      .Positive();
  t.Add("mesh_format", &O::mesh_format, "format of the reconstructed meshes (samp inspect --format)")
      .Internal()
      .Choices(kMeshFormats);
  t.Add("num_distance_samples", &O::num_distance_samples, "points sampled on each surface for the distances")
      .Internal()
      .AtLeast(100);
  t.Add("seed", &O::seed, "Seed of the surface sampling for point-to-point distances");
  return t;
}

OptionTable<PictureOptions> MakePictureTable() {
  using O = PictureOptions;
  OptionTable<O> t("PictureOptions");
  t.Add("output_folder", &O::output_folder, "eigen_shapes.png and shapes.png go here (samp inspect --pictures)")
      .Internal()
      .Rule("given", [](const O& o) { return !o.output_folder.empty(); });
  // The help is samp inspect's.
  t.Add("sdf_folder", &O::sdf_folder,
        "Per-model SDFs (samp train --sdf-dir) for the sheet; with --cad-dir too, the CAD models are drawn beside "
        "their stored SDFs")
      .Flag("sdf-dir")
      .ExistingDirectory();
  t.Add("cad_folder", &O::cad_folder, "CAD folder for the sheet (scanned as the trainer does when no --sdf-dir)")
      .Flag("cad-dir")
      .ExistingDirectory();
  t.Add("manifest_path", &O::manifest_path, "canonicalisation of CAD files (samp inspect --manifest)").Internal();
  t.Add("num_sheet_shapes", &O::num_sheet_shapes, "Number of training shapes on the sheet")
      .Flag("num-shapes")
      .AtLeast(1)
      .AtMost(50);
  t.AddList("sigmas", &O::sigmas, "Columns of the eigen-shape picture, multiples of sigma, comma-separated")
      .Separator(',')
      .Rule("a non-empty list", [](const O& o) { return !o.sigmas.empty(); });
  t.Add("max_components", &O::max_components, "rows of the eigen-shape picture, 0 = all R (samp inspect --components)")
      .Internal()
      .NonNegative();
  t.Add("cell_width", &O::cell_width, "one picture cell, px").Internal().AtLeast(120);
  t.Add("cell_height", &O::cell_height, "... px").Internal().AtLeast(90);
  return t;
}

OptionTable<InspectOptions> MakeInspectTable() {
  using O = InspectOptions;
  OptionTable<O> t("InspectOptions");
  // The help is samp inspect's.
  t.Add("model_path", &O::model_path, "The model file (.vdb written by samp train)")
      .Positional("MODEL")
      .Required()
      .ExistingFile();
  t.Add("meshes_folder", &O::meshes_folder,
        "Write the zero level sets of the mean and of mean + k sigma_i w_i for each component into this folder "
        "(object frame, metres)")
      .Flag("meshes");
  t.Add("encode_input", &O::encode_input,
        "Project into the manifold: a CAD file (scanned as the trainer does), a per-model SDF .vdb (samp train "
        "--sdf-dir), or a folder of them (a table for every file)")
      .Flag("encode");
  t.Add("encode_folder", &O::encode_folder, "With --encode: write each reconstructed mesh and encode.csv here")
      .Flag("out")
      .Rule("empty without --encode", [](const O& o) { return o.encode_folder.empty() || !o.encode_input.empty(); });
  t.Add("manifest_path", &O::manifest_path, "Canonicalisation manifest for CAD files (--encode, --cad-dir)")
      .Flag("manifest")
      .ExistingFile();
  t.Add("pictures_folder", &O::pictures_folder,
        "Write PNGs here: eigen_shapes.png (rows = components, columns = sigmas) and, with --sdf-dir or --cad-dir, "
        "shapes.png (a Figure-2-like sheet)")
      .Flag("pictures");
  t.Add("html_path", &O::html_path,
        "Write an interactive page (one self-contained HTML file) with a slider per eigen-shape; the surface is "
        "extracted in the browser")
      .Flag("html");
  return t;
}

}  // namespace

const OptionTable<EigenShapeMeshOptions>& EigenShapeMeshOptionTable() {
  static const OptionTable<EigenShapeMeshOptions> table = MakeEigenShapeMeshTable();
  return table;
}

const OptionTable<EncodeOptions>& EncodeOptionTable() {
  static const OptionTable<EncodeOptions> table = MakeEncodeTable();
  return table;
}

const OptionTable<PictureOptions>& PictureOptionTable() {
  static const OptionTable<PictureOptions> table = MakePictureTable();
  return table;
}

const OptionTable<InspectOptions>& InspectOptionTable() {
  static const OptionTable<InspectOptions> table = MakeInspectTable();
  return table;
}

void InspectOptions::Check() const { InspectOptionTable().Check(*this); }

}  // namespace samp
