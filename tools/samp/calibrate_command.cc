// `samp calibrate-detector`: detections of sequences + ground-truth tracking
// labels -> a detector model JSON (docs/detector_calibration.md) for
// `samp fit --detector-model`.
#include <iostream>
#include <memory>

#include "libsamp/data/calibration_option_table.h"
#include "libsamp/data/detector_noise.h"
#include "tools/samp/commands.h"
#include "tools/samp/option_cli.h"

namespace samp::tools {

void RegisterCalibrateCommand(CLI::App* app) {
  struct Args {
    DetectorCalibrationOptions options;
    std::string out;
  };
  auto args = std::make_shared<Args>();
  CLI::App* command = app->add_subcommand(
      "calibrate-detector",
      "Measure a 3D car detector's noise model (position along/across the ray and vertical by distance,\n"
      "box dimensions with biases, yaw, flips, misses, false positives) from its detections in sequence\n"
      "directories and ground-truth tracking labels (KITTI label_02); writes the JSON that\n"
      "`samp fit --detector-model` reads (docs/detector_calibration.md).");
  command->add_option("--seq", args->options.sequences, "Sequence directory (detections/); repeatable")
      ->required()
      ->check(CLI::ExistingDirectory);
  command->add_option("--labels", args->options.truth_labels,
                      "Ground-truth KITTI tracking label file, one per --seq (default: SEQ/gt/label_02/<seq>.txt)")
      ->check(CLI::ExistingFile);
  command->add_option("--match-distance", args->options.match_distance,
                      "A detection matches a true box within this horizontal distance, m")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("-o,--out", args->out, "Detector model JSON to write")->required();
  const std::string noise_group = "Estimation (DetectorNoiseOptions; docs/detector_calibration.md, \"Options\")";
  // Every field, --bin-edges too, from the table (data/calibration_option_table.h).
  AddTableOptions(command, DetectorNoiseOptionTable().Bind(&args->options.noise), "", noise_group);
  AddCommonOptions(command);
  command->callback([args] {
    DetectorCalibrationSummary summary;
    const DetectorNoiseModel model = CalibrateDetectorFromTruth(args->options, &summary);
    WriteDetectorNoiseModel(args->out, model);
    std::cout << summary.BriefReport() << "\n" << model.BriefReport() << "\nwrote " << args->out << std::endl;
  });
}

}  // namespace samp::tools
