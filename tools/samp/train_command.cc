// `samp train`: a folder of CAD cars -> a PCA shape-manifold model file.
#include <iostream>
#include <memory>

#include "libsamp/core/log.h"
#include "libsamp/model/pca_option_table.h"
#include "libsamp/model/train_option_table.h"
#include "libsamp/model/trainer.h"
#include "libsamp/scan/scan_option_table.h"
#include "libsamp/sdf/sdf_option_table.h"
#include "tools/samp/commands.h"
#include "tools/samp/option_cli.h"

namespace samp::tools {
namespace {

// The options of PCA, scan and SDF as one list (`samp train --help-options markdown`).
std::vector<OptionInfo> TrainOptionInfos() {
  std::vector<OptionInfo> infos;
  for (const std::vector<OptionInfo>& part :
       {PcaOptionTable().Describe(), ScanOptionTable().Describe(), SdfOptionTable().Describe()}) {
    infos.insert(infos.end(), part.begin(), part.end());
  }
  return infos;
}

}  // namespace

void RegisterTrainCommand(CLI::App* app) {
  auto options = std::make_shared<TrainOptions>();
  CLI::App* command = app->add_subcommand(
      "train",
      "Train a shape manifold (PCA of signed distance fields) from a folder of CAD cars.\n"
      "Each mesh file (any format assimp reads) is brought into the canonical object frame,\n"
      "scanned with Embree from viewpoints on a sphere, turned into an SDF on the car grid;\n"
      "models that fail are skipped with a reason. See docs/training.md.");
  // TrainOptions' own fields from its table (model/train_option_table.h), each
  // at its place among the other options.
  const std::vector<OptionBinding> run = TrainOptionTable().Bind(options.get());
  const std::string run_group = "Options";
  AddTableOptions(command,
                  Only(run, {"cad_folder", "output_path", "manifest", "preset", "sdf_folder", "voxel_size",
                             "grid_length", "grid_height", "grid_width", "resolution"}),
                  "", run_group);
  // ScanOptions, SdfOptions, the quality gate and PcaOptions: every field from
  // their tables (scan/scan_option_table.h, sdf/sdf_option_table.h, model/pca_option_table.h).
  TrainOptions& o = *options;
  AddTableOptions(command, PcaOptionTable().Bind(&o.pca), "", "PCA (PcaOptions)");
  AddTableOptions(command, ScanOptionTable().Bind(&o.scan), "", "Scan (ScanOptions; docs/training.md)");
  AddTableOptions(command, SdfOptionTable().Bind(&o.sdf), "", "SDF (SdfOptions; docs/sdf.md)");
  AddTableOptions(command, SdfQualityOptionTable().Bind(&o.gate), "gate-",
                  "Quality gate (SdfQualityOptions; docs/training.md)");
  AddHelpOptions(command, {{"markdown", TrainOptionInfos(), ""},
                           {"gate-markdown", SdfQualityOptionTable().Describe(), "gate-"},
                           {"run-markdown", TrainOptionTable().Describe(), ""}});
  AddTableOptions(command, Only(run, {"size_variants", "num_threads"}), "", run_group);
  AddCommonOptions(command);
  command->callback([options] {
    options->show_progress = GetLogLevel() <= LogLevel::kInfo;
    const TrainSummary summary = TrainShapeModel(*options);
    std::cout << summary.BriefReport();
    std::cout << "wrote " << options->output_path << std::endl;
  });
}

}  // namespace samp::tools
