// `samp view`: a `samp fit` output folder or a model file -> one self-contained
// index.html (three.js inlined; opens from disk). docs/fitting.md, "Viewer".
#include <filesystem>
#include <iostream>
#include <memory>

#include "libsamp/core/error.h"
#include "libsamp/model/shape_model.h"
#include "libsamp/viz/fit_pictures.h"
#include "libsamp/viz/html_viewer.h"
#include "tools/samp/commands.h"

namespace samp::tools {

void RegisterViewCommand(CLI::App* app) {
  struct Args {
    std::string input;
    std::string html_path;
    bool pictures = false;
    double tau = 0.2;
    int max_points = 0;
  };
  auto args = std::make_shared<Args>();
  CLI::App* command = app->add_subcommand(
      "view",
      "Write an interactive viewer as one self-contained HTML file (three.js inlined, works\n"
      "offline). OUT = a `samp fit` output folder: points, meshes, trajectories and detections\n"
      "over the frames (with ground truth in the sequence: true boxes, error colouring);\n"
      "writes OUT/index.html. OUT = a model file (.vdb): eigen-shape sliders (needs -o).");
  command->add_option("OUT", args->input, "A samp fit output folder, or a model file")->required()->check(
      CLI::ExistingPath);
  command->add_option("-o,--html", args->html_path, "The page to write (default: OUT/index.html for a fit)");
  command->add_flag("--pictures", args->pictures, "Also write the PNG pictures of a fit (OUT/pictures/)");
  command->add_option("--tau", args->tau, "Error colouring threshold tau, m")->capture_default_str()->check(
      CLI::PositiveNumber);
  command->add_option("--max-points", args->max_points,
                      "At most this many points per track and frame in the page (0 = all)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  AddCommonOptions(command);
  command->callback([args] {
    if (std::filesystem::is_directory(args->input)) {
      FitVisualsOptions options;
      options.output_dir = args->input;
      options.pictures = args->pictures;
      options.html_path = args->html_path;
      options.load.error_tau = args->tau;
      options.page.max_points_per_frame = args->max_points;
      const FitVisualsSummary summary = WriteFitVisuals(options);
      std::cout << summary.BriefReport() << std::endl;
      return;
    }
    SAMP_CHECK(!args->html_path.empty()) << "view: a model file needs -o PAGE.html";
    SAMP_CHECK(!args->pictures) << "view: --pictures is for fit output folders";
    const ShapeModel model = ShapeModel::Load(args->input);
    InspectHtmlOptions options;
    options.model_path = args->input;
    WriteInspectViewer(args->html_path, model, options);
    std::cout << "wrote " << args->html_path << std::endl;
  });
}

}  // namespace samp::tools
