// `samp view`: a `samp fit` output folder or a model file -> one self-contained
// index.html (three.js inlined; opens from disk). docs/fitting.md, "Viewer".
#include <filesystem>
#include <iostream>
#include <memory>

#include "libsamp/core/error.h"
#include "libsamp/model/shape_model.h"
#include "libsamp/viz/fit_pictures.h"
#include "libsamp/viz/html_viewer.h"
#include "libsamp/viz/view_option_table.h"
#include "tools/samp/commands.h"
#include "tools/samp/option_cli.h"

namespace samp::tools {

void RegisterViewCommand(CLI::App* app) {
  auto options = std::make_shared<FitVisualsOptions>();
  options->pictures = false;
  CLI::App* command = app->add_subcommand(
      "view",
      "Write an interactive viewer as one self-contained HTML file (three.js inlined, works\n"
      "offline). OUT = a `samp fit` output folder: points, meshes, trajectories and detections\n"
      "over the frames (with ground truth in the sequence: true boxes, error colouring);\n"
      "writes OUT/index.html. OUT = a model file (.vdb): eigen-shape sliders (needs -o).");
  // FitVisualsOptions with its load and page options: their tables (viz/view_option_table.h).
  const std::vector<OptionBinding> view = FitVisualsOptionTable().Bind(options.get());
  AddTableOptions(command, Only(view, {"output_dir", "html_path", "pictures", "load.error_tau",
                                       "page.max_points_per_frame"}),
                  "", "Options");
  AddHelpOptions(command, {{"markdown", FitVisualsOptionTable().Describe(), ""}});
  AddCommonOptions(command);
  command->callback([options] {
    if (std::filesystem::is_directory(options->output_dir)) {
      const FitVisualsSummary summary = WriteFitVisuals(*options);
      std::cout << summary.BriefReport() << std::endl;
      return;
    }
    SAMP_CHECK(!options->html_path.empty()) << "view: a model file needs -o PAGE.html";
    SAMP_CHECK(!options->pictures) << "view: --pictures is for fit output folders";
    const ShapeModel model = ShapeModel::Load(options->output_dir);
    InspectHtmlOptions page;
    page.model_path = options->output_dir;
    WriteInspectViewer(options->html_path, model, page);
    std::cout << "wrote " << options->html_path << std::endl;
  });
}

}  // namespace samp::tools
