// `samp eval`: fitted tracks on synthetic sequences -> the paper's shape and pose tables and plots.
#include <iostream>
#include <memory>

#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/data/kitti_tracking.h"
#include "libsamp/eval/eval_option_table.h"
#include "libsamp/eval/evaluation.h"
#include "libsamp/viz/fit_pictures.h"
#include "tools/samp/commands.h"
#include "tools/samp/option_cli.h"

namespace samp::tools {

void RegisterEvalCommand(CLI::App* app) {
  struct Args {
    EvalOptions options;
    std::vector<std::string> results;
    bool pictures = false;
    std::string kitti_root;
    std::string kitti_sequences = "all";
  };
  auto args = std::make_shared<Args>();
  EvalOptions& o = args->options;
  CLI::App* command = app->add_subcommand(
      "eval",
      "Evaluate fitted tracks on synthetic sequences with ground truth (docs/evaluation.md):\n"
      "accuracy, completeness and F1 of the visible surface over a sweep of tau, translation and\n"
      "yaw errors by distance; baselines: raw stereo points and the input detections.\n"
      "Both matchings (per track, per frame), CLEAR-MOT tracking figures, per-car diagnostics.\n"
      "Writes results.md, results.json, shape.csv, pose.csv, per_object.csv, per_car.csv,\n"
      "tracking.csv and PNG plots.");
  command->add_option("--seq", o.sequences,
                      "A synthetic sequence folder (with gt/), or ROOT/image_02/<seq> of KITTI tracking's layout; "
                      "repeatable")
      ->check(CLI::ExistingDirectory);
  command->add_option("--result", args->results,
                      "NAME=DIR: a `samp fit` output folder to evaluate under NAME; repeatable")
      ->expected(0, -1);
  command->add_option("-o,--out", o.output_folder, "Output folder for tables and plots")->required();
  command->add_option("--taus", o.taus, "Distance thresholds tau of the shape sweep, m, increasing")
      ->capture_default_str()
      ->delimiter(',');
  // The scalar options: EvalOptions' table (eval/eval_option_table.h).
  AddTableOptions(command, EvalOptionTable().Bind(&o), "", "Evaluation (EvalOptions; docs/evaluation.md)");
  AddHelpOptions(command, {{"markdown", EvalOptionTable().Describe(), ""}});
  const std::string kitti_group = "KITTI tracking's layout (pose and tracking figures only; docs/evaluation.md)";
  command->add_option("--kitti-tracking", args->kitti_root,
                      "KITTI tracking folder (training/: image_02, calib, label_02 as the ground truth)")
      ->check(CLI::ExistingDirectory)
      ->group(kitti_group);
  command->add_option("--sequence", args->kitti_sequences,
                      "With --kitti-tracking: sequences, comma-separated (0004,0011) or all")
      ->capture_default_str()
      ->group(kitti_group);
  command->add_flag("--pictures", args->pictures,
                    "Per result and car: the fitted surface coloured by its distance to the true one "
                    "at --tau (OUT/error_surfaces/NAME/<seq>/track_<id>_error.png)");
  AddCommonOptions(command);
  command->callback([args, command] {
    SAMP_CHECK(command->count("--sequence") == 0 || !args->kitti_root.empty())
        << "--sequence names sequences of --kitti-tracking; give it (or --seq)";
    EvalOptions options = args->options;
    if (!args->kitti_root.empty()) {
      for (const std::string& folder : KittiTrackingSequenceFolders(args->kitti_root, args->kitti_sequences))
        options.sequences.push_back(folder);
    }
    if (options.sequences.empty()) throw CLI::RequiredError("--seq or --kitti-tracking");
    for (const std::string& result : args->results) {
      const size_t eq = result.find('=');
      SAMP_CHECK(eq != std::string::npos && eq > 0 && eq + 1 < result.size())
          << "eval: --result must be NAME=DIR, got '" << result << "'";
      options.results.emplace_back(result.substr(0, eq), result.substr(eq + 1));
    }
    const EvalSummary summary = Evaluate(options);
    std::cout << summary.markdown << "\n" << summary.BriefReport() << "\nwrote " << options.output_folder
              << std::endl;
    if (args->pictures) {
      for (const auto& [name, folder] : options.results) {
        FitVisualsOptions visuals;
        visuals.output_dir = folder;
        visuals.html = false;
        visuals.only_error_surfaces = true;
        visuals.pictures_folder = options.output_folder + "/error_surfaces/" + name;
        visuals.load.error_tau = options.headline_tau;
        std::cout << name << ": " << WriteFitVisuals(visuals).BriefReport() << std::endl;
      }
    }
  });
}

}  // namespace samp::tools
