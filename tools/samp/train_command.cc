// `samp train`: a folder of CAD cars -> a PCA shape-manifold model file.
#include <iostream>
#include <memory>

#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/model/pca_option_table.h"
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
  struct Args {
    TrainOptions options;
    double voxel_size = 0.1;
    int resolution = 400;
    std::vector<std::vector<double>> size_variants;
  };
  auto args = std::make_shared<Args>();
  TrainOptions& o = args->options;
  o.num_threads = 0;
  CLI::App* command = app->add_subcommand(
      "train",
      "Train a shape manifold (PCA of signed distance fields) from a folder of CAD cars.\n"
      "Each mesh file (any format assimp reads) is brought into the canonical object frame,\n"
      "scanned with Embree from viewpoints on a sphere, turned into an SDF on the car grid;\n"
      "models that fail are skipped with a reason. See docs/training.md.");
  command->add_option("CAD_FOLDER", o.cad_folder,
                      "Folder searched recursively for mesh files (other files are ignored)")
      ->required()
      ->check(CLI::ExistingDirectory);
  command->add_option("-o,--output", o.output_path,
                      "The model file to write (.vdb, written atomically; docs/model_format.md)")
      ->required();
  command->add_option("--manifest", o.manifest_path,
                      "JSON manifest: per file name, scale or target length, up/forward axes, "
                      "skip (docs/canonical_frame.md); without it axes are auto-detected")
      ->check(CLI::ExistingFile);
  command->add_option("--preset", o.preset,
                      "Canonicalisation of the files no manifest entry lists: shapenet "
                      "(ShapeNetCore v2: +y up, front -z, unit diagonal -> 4.49 m) or apollocar3d "
                      "(car_models_json: metres, y down, front +z); docs/canonical_frame.md")
      ->check(CLI::IsMember({"shapenet", "apollocar3d"}));
  command->add_option("--sdf-dir", o.sdf_folder,
                      "Also write each model's SDF as <name>.vdb into this folder");
  command->add_option("--voxel", args->voxel_size,
                      "Voxel size in metres of the car grid (a 6.0 x 2.8 x 2.8 m box around the "
                      "canonical car)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--resolution", args->resolution,
                      "Width and height in pixels (rays) of each scan view (scan.width, scan.height)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  // ScanOptions, SdfOptions, the quality gate and PcaOptions: every field from
  // their tables (scan/scan_option_table.h, sdf/sdf_option_table.h, model/pca_option_table.h).
  AddTableOptions(command, PcaOptionTable().Bind(&o.pca), "", "PCA (PcaOptions)");
  AddTableOptions(command, ScanOptionTable().Bind(&o.scan), "", "Scan (ScanOptions; docs/training.md)");
  AddTableOptions(command, SdfOptionTable().Bind(&o.sdf), "", "SDF (SdfOptions; docs/sdf.md)");
  AddTableOptions(command, SdfQualityOptionTable().Bind(&o.gate), "gate-",
                  "Quality gate (SdfQualityOptions; docs/training.md)");
  AddHelpOptions(command, {{"markdown", TrainOptionInfos(), ""},
                           {"gate-markdown", SdfQualityOptionTable().Describe(), "gate-"}});
  command->add_option("--size-variant", args->size_variants,
                      "Also train on each car stretched by these factors of length, height and width "
                      "(repeatable: one copy of every car per occurrence; docs/training.md, Size variants)")
      ->expected(3)
      ->check(CLI::Range(0.5, 2.0));
  command->add_option("--threads", o.num_threads, "Worker threads (0 = all cores)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  AddCommonOptions(command);
  command->callback([args] {
    TrainOptions options = args->options;
    options.grid = GridSpec::CarDefault(args->voxel_size);
    options.scan.width = options.scan.height = args->resolution;
    for (const std::vector<double>& f : args->size_variants) {
      SAMP_CHECK(f.size() == 3) << "--size-variant takes 3 factors (length height width)";
      options.size_variants.emplace_back(f[0], f[1], f[2]);
    }
    options.show_progress = GetLogLevel() <= LogLevel::kInfo;
    const TrainSummary summary = TrainShapeModel(options);
    std::cout << summary.BriefReport();
    std::cout << "wrote " << options.output_path << std::endl;
  });
}

}  // namespace samp::tools
