// `samp inspect`: summary, eigen-shape meshes, encoding and pictures of a
// shape-manifold model file (docs/inspect.md).
#include <iostream>
#include <memory>

#include "libsamp/model/shape_model.h"
#include "libsamp/viz/html_viewer.h"
#include "libsamp/viz/inspect.h"
#include "libsamp/viz/inspect_option_table.h"
#include "tools/samp/commands.h"
#include "tools/samp/option_cli.h"

namespace samp::tools {

namespace {

// The callback of `samp inspect`: the summary, then each part asked for.
void RunInspectCommand(const InspectOptions& args) {
  args.Check();
  const ShapeModel model = ShapeModel::Load(args.model_path);
  std::cout << SummarizeModel(model, args.model_path);
  if (!args.meshes_folder.empty()) {
    EigenShapeMeshOptions options = args.meshes;
    options.output_folder = args.meshes_folder;
    std::cout << "\n" << WriteEigenShapeMeshes(model, options).BriefReport();
  }
  if (!args.encode_input.empty()) {
    EncodeOptions options = args.encode;
    options.input = args.encode_input;
    options.output_folder = args.encode_folder;
    options.manifest_path = args.manifest_path;
    options.mesh_format = args.meshes.format;
    std::cout << "\n" << EncodeShapes(model, options).BriefReport();
  }
  if (!args.pictures_folder.empty()) {
    PictureOptions options = args.pictures;
    options.output_folder = args.pictures_folder;
    options.manifest_path = args.manifest_path;
    options.max_components = args.meshes.max_components;
    std::cout << "\n" << WritePictures(model, options).BriefReport();
  }
  if (!args.html_path.empty()) {
    InspectHtmlOptions options;
    options.model_path = args.model_path;
    options.max_components = args.meshes.max_components;
    WriteInspectViewer(args.html_path, model, options);
    std::cout << "\nwrote " << args.html_path << "\n";
  }
}

}  // namespace

void RegisterInspectCommand(CLI::App* app) {
  auto options = std::make_shared<InspectOptions>();
  CLI::App* command = app->add_subcommand(
      "inspect",
      "Inspect a shape manifold: print its summary (grid, R, eigenvalues with explained and\n"
      "cumulative variance, training shapes, trainer options); optionally export eigen-shape\n"
      "meshes, project CAD models or SDFs into the manifold, draw PNG pictures.\n"
      "See docs/inspect.md.");
  // InspectOptions and its parts' options from their tables (viz/inspect_option_table.h),
  // in the order of the parts.
  const std::vector<OptionBinding> own = InspectOptionTable().Bind(options.get());
  const std::vector<OptionBinding> meshes = EigenShapeMeshOptionTable().Bind(&options->meshes);
  const std::vector<OptionBinding> encode = EncodeOptionTable().Bind(&options->encode);
  const std::vector<OptionBinding> pictures = PictureOptionTable().Bind(&options->pictures);
  const std::string group = "Options";
  AddTableOptions(command, Only(own, {"model_path", "meshes_folder"}), "", group);
  AddTableOptions(command, Only(meshes, {"ks", "format", "max_components"}), "", group);
  AddTableOptions(command, Only(own, {"encode_input", "encode_folder", "manifest_path"}), "", group);
  AddTableOptions(command, Only(encode, {"prior_weight", "near_surface_voxels", "seed"}), "", group);
  AddTableOptions(command, Only(own, {"pictures_folder"}), "", group);
  AddTableOptions(command, Only(pictures, {"sdf_folder", "cad_folder", "num_sheet_shapes", "sigmas"}), "", group);
  AddTableOptions(command, Only(own, {"html_path"}), "", group);
  AddHelpOptions(command, {{"markdown", InspectOptionTable().Describe(), ""},
                           {"meshes-markdown", EigenShapeMeshOptionTable().Describe(), ""},
                           {"encode-markdown", EncodeOptionTable().Describe(), ""},
                           {"pictures-markdown", PictureOptionTable().Describe(), ""}});
  AddCommonOptions(command);
  command->callback([options] { RunInspectCommand(*options); });
}

}  // namespace samp::tools
