// `samp calibrate-detector`: detections of sequences + ground-truth tracking
// labels -> a detector model JSON (docs/detector_calibration.md) for
// `samp fit --detector-model`, and its plot of the error against distance.
#include <filesystem>
#include <iostream>
#include <memory>

#include "libsamp/core/error.h"
#include "libsamp/data/calibration_option_table.h"
#include "libsamp/data/detector_noise.h"
#include "libsamp/data/sequence_option_table.h"
#include "libsamp/viz/detector_noise_plot.h"
#include "tools/samp/commands.h"
#include "tools/samp/option_cli.h"

namespace samp::tools {

void RegisterCalibrateCommand(CLI::App* app) {
  struct Args {
    DetectorCalibrationOptions options;
    std::string out;
    std::string plot;  // "" = the JSON's path with .png
    bool no_plot = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* command = app->add_subcommand(
      "calibrate-detector",
      "Measure a 3D car detector's noise model (position along/across the ray and vertical by distance,\n"
      "box dimensions with biases, yaw, flips, misses, false positives) from its detections (a sequence's\n"
      "detections/, or --detections: e.g. a tracker's KITTI tracking result file, its track ids ignored)\n"
      "and ground-truth tracking labels (KITTI label_02; detections in its DontCare regions are not\n"
      "false positives); writes the JSON that\n"
      "`samp fit --detector-model` reads and a PNG of the error against distance beside it\n"
      "(docs/detector_calibration.md).");
  const std::string input_group = "Input (docs/sequence_format.md)";
  command
      ->add_option("--seq", args->options.sequences,
                   "Sequence directory (samp's layout, or KITTI tracking's ROOT/image_02/<seq>); repeatable")
      ->required()
      ->check(CLI::ExistingDirectory)
      ->group(input_group);
  // SequenceOptions' own options (--detections, --detection-format, --min-score, --types): its table
  // (data/sequence_option_table.h), as `samp fit` takes them.
  AddTableOptions(command, SequenceOptionTable().Bind(&args->options.sequence), "", input_group);
  command
      ->add_option("--labels", args->options.truth_labels,
                   "Ground-truth KITTI tracking label file, one per --seq (default: SEQ/gt/label_02/<seq>.txt; "
                   "KITTI tracking: ROOT/label_02/<seq>.txt)")
      ->check(CLI::ExistingFile)
      ->group(input_group);
  command->add_option("--match-distance", args->options.match_distance,
                      "A detection matches a true box within this horizontal distance, m")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--dont-care-overlap", args->options.dont_care_overlap,
                      "A detection without a true box is not counted as a false positive when at least this share "
                      "(0-1) of its projected 2D box lies inside its frame's DontCare boxes (KITTI label_02); "
                      "counted in the JSON's samples.dont_care_ignored")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  command->add_option("-o,--out", args->out, "Detector model JSON to write")->required();
  CLI::Option* plot =
      command->add_option("--plot", args->plot,
                          "PNG of the error against distance to write beside it (default: the JSON's path with "
                          ".png; docs/detector_calibration.md, \"The plot\")");
  command->add_flag("--no-plot", args->no_plot, "Write no plot")->excludes(plot);
  const std::string noise_group = "Estimation (DetectorNoiseOptions; docs/detector_calibration.md, \"Options\")";
  // Every field, --bin-edges too, from the table (data/calibration_option_table.h).
  AddTableOptions(command, DetectorNoiseOptionTable().Bind(&args->options.noise), "", noise_group);
  AddCommonOptions(command);
  command->callback([args] {
    std::string plot_path;
    if (!args->no_plot) {
      plot_path = args->plot.empty() ? std::filesystem::path(args->out).replace_extension(".png").string() : args->plot;
      SAMP_CHECK(plot_path != args->out) << "calibrate-detector: the plot " << plot_path
                                         << " would replace the model JSON -o " << args->out
                                         << ": give --plot FILE (or --no-plot)";
    }
    DetectorCalibrationSummary summary;
    const DetectorNoiseModel model = CalibrateDetectorFromTruth(args->options, &summary);
    WriteDetectorNoiseModel(args->out, model);
    std::cout << summary.BriefReport() << "\n" << model.BriefReport() << "\nwrote " << args->out << std::endl;
    if (!plot_path.empty()) {
      WriteDetectorNoisePlot(plot_path, model);
      std::cout << "wrote " << plot_path << std::endl;
    }
  });
}

}  // namespace samp::tools
