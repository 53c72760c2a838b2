// `samp inspect`: summary, eigen-shape meshes, encoding and pictures of a
// shape-manifold model file (docs/inspect.md).
#include <iostream>
#include <memory>

#include "libsamp/core/error.h"
#include "libsamp/model/shape_model.h"
#include "libsamp/viz/html_viewer.h"
#include "libsamp/viz/inspect.h"
#include "tools/samp/commands.h"

namespace samp::tools {

void RegisterInspectCommand(CLI::App* app) {
  struct Args {
    std::string model_path;
    std::string meshes_folder;
    EigenShapeMeshOptions meshes;
    EncodeOptions encode;
    std::string encode_out;
    PictureOptions pictures;
    std::string pictures_folder;
    std::string manifest_path;
    std::string html_path;
  };
  auto args = std::make_shared<Args>();
  CLI::App* command = app->add_subcommand(
      "inspect",
      "Inspect a shape manifold: print its summary (grid, R, eigenvalues with explained and\n"
      "cumulative variance, training shapes, trainer options); optionally export eigen-shape\n"
      "meshes, project CAD models or SDFs into the manifold, draw PNG pictures.\n"
      "See docs/inspect.md.");
  command->add_option("MODEL", args->model_path, "The model file (.vdb written by samp train)")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("--meshes", args->meshes_folder,
                      "Write the zero level sets of the mean and of mean + k sigma_i w_i for each "
                      "component into this folder (object frame, metres)");
  command->add_option("--k", args->meshes.ks,
                      "Multiples of sigma for --meshes, comma-separated")
      ->delimiter(',')
      ->capture_default_str();
  command->add_option("--format", args->meshes.format, "Mesh format for --meshes and --encode")
      ->check(CLI::IsMember({"ply", "obj", "glb"}))
      ->capture_default_str();
  command->add_option("--components", args->meshes.max_components,
                      "Components for --meshes and the eigen-shape picture (0 = all R)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--encode", args->encode.input,
                      "Project into the manifold: a CAD file (scanned as the trainer does), a "
                      "per-model SDF .vdb (samp train --sdf-dir), or a folder of them (a table "
                      "for every file)");
  command->add_option("--out", args->encode_out,
                      "With --encode: write each reconstructed mesh and encode.csv here");
  command->add_option("--manifest", args->manifest_path,
                      "Canonicalisation manifest for CAD files (--encode, --cad-dir)")
      ->check(CLI::ExistingFile);
  command->add_option("--prior-weight", args->encode.prior_weight,
                      "Weight lambda of the Gaussian prior in the projection: z_i = w_i^T(x - mu) "
                      "/ (1 + lambda / sigma_i^2); 0 = least squares")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--near", args->encode.near_surface_voxels,
                      "RMS SDF error over voxels with |sdf| below this many voxels")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--seed", args->encode.seed,
                      "Seed of the surface sampling for point-to-point distances")
      ->capture_default_str();
  command->add_option("--pictures", args->pictures_folder,
                      "Write PNGs here: eigen_shapes.png (rows = components, columns = sigmas) "
                      "and, with --sdf-dir or --cad-dir, shapes.png (a Figure-2-like sheet)");
  command->add_option("--sdf-dir", args->pictures.sdf_folder,
                      "Per-model SDFs (samp train --sdf-dir) for the sheet; with --cad-dir too, the "
                      "CAD models are drawn beside their stored SDFs")
      ->check(CLI::ExistingDirectory);
  command->add_option("--cad-dir", args->pictures.cad_folder,
                      "CAD folder for the sheet (scanned as the trainer does when no --sdf-dir)")
      ->check(CLI::ExistingDirectory);
  command->add_option("--num-shapes", args->pictures.num_sheet_shapes,
                      "Number of training shapes on the sheet")
      ->capture_default_str()
      ->check(CLI::Range(1, 50));
  command->add_option("--sigmas", args->pictures.sigmas,
                      "Columns of the eigen-shape picture, multiples of sigma, comma-separated")
      ->delimiter(',')
      ->capture_default_str();
  command->add_option("--html", args->html_path,
                      "Write an interactive page (one self-contained HTML file) with a slider per "
                      "eigen-shape; the surface is extracted in the browser");
  AddCommonOptions(command);
  command->callback([args] {
    const ShapeModel model = ShapeModel::Load(args->model_path);
    std::cout << SummarizeModel(model, args->model_path);
    if (!args->meshes_folder.empty()) {
      EigenShapeMeshOptions options = args->meshes;
      options.output_folder = args->meshes_folder;
      std::cout << "\n" << WriteEigenShapeMeshes(model, options).BriefReport();
    }
    if (!args->encode.input.empty()) {
      EncodeOptions options = args->encode;
      options.output_folder = args->encode_out;
      options.manifest_path = args->manifest_path;
      options.mesh_format = args->meshes.format;
      std::cout << "\n" << EncodeShapes(model, options).BriefReport();
    } else {
      SAMP_CHECK(args->encode_out.empty()) << "inspect: --out needs --encode";
    }
    if (!args->pictures_folder.empty()) {
      PictureOptions options = args->pictures;
      options.output_folder = args->pictures_folder;
      options.manifest_path = args->manifest_path;
      options.max_components = args->meshes.max_components;
      std::cout << "\n" << WritePictures(model, options).BriefReport();
    }
    if (!args->html_path.empty()) {
      InspectHtmlOptions options;
      options.model_path = args->model_path;
      options.max_components = args->meshes.max_components;
      WriteInspectViewer(args->html_path, model, options);
      std::cout << "\nwrote " << args->html_path << "\n";
    }
  });
}

}  // namespace samp::tools
