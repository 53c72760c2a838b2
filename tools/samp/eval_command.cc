// `samp eval`: fitted tracks on synthetic sequences -> the paper's shape and pose tables and plots.
#include <iostream>
#include <memory>

#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/data/kitti_tracking.h"
#include "libsamp/eval/evaluation.h"
#include "libsamp/viz/fit_pictures.h"
#include "tools/samp/commands.h"

namespace samp::tools {

void RegisterEvalCommand(CLI::App* app) {
  struct Args {
    EvalOptions options;
    std::vector<std::string> results;
    bool no_stereo = false, no_detections = false;
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
  const std::string kitti_group = "KITTI tracking's layout (pose and tracking figures only; docs/evaluation.md)";
  command->add_option("--kitti-tracking", args->kitti_root,
                      "KITTI tracking folder (training/: image_02, calib, label_02 as the ground truth)")
      ->check(CLI::ExistingDirectory)
      ->group(kitti_group);
  command->add_option("--sequence", args->kitti_sequences,
                      "With --kitti-tracking: sequences, comma-separated (0004,0011) or all")
      ->capture_default_str()
      ->group(kitti_group);
  command->add_option("--detections", o.detections_path,
                      "The detections of the detection baseline: a file (one sequence) or a folder with <seq>.txt "
                      "(formats of samp fit --detections)")
      ->check(CLI::ExistingPath)
      ->group(kitti_group);
  command->add_option("--min-box-height", o.min_box_height_px,
                      "A true car is evaluated when its 2D box is at least this tall, px (KITTI moderate: 25)")
      ->capture_default_str()
      ->group(kitti_group);
  command->add_option("--max-occlusion", o.max_occlusion, "... its occlusion level at most this (0-3)")
      ->capture_default_str()
      ->group(kitti_group);
  command->add_option("--max-truncation", o.max_truncation, "... and its truncation at most this (0-1)")
      ->capture_default_str()
      ->group(kitti_group);
  command->add_option("--result", args->results,
                      "NAME=DIR: a `samp fit` output folder to evaluate under NAME; repeatable")
      ->expected(0, -1);
  command->add_option("-o,--out", o.output_folder, "Output folder for tables and plots")->required();
  command->add_option("--taus", o.taus, "Distance thresholds tau of the shape sweep, m")
      ->capture_default_str()
      ->delimiter(',');
  command->add_option("--tau", o.headline_tau, "Headline tau of the table, m (one of --taus)")
      ->capture_default_str();
  command->add_option("--window", o.distance_window, "Width of the pose distance windows, m")
      ->capture_default_str();
  command->add_option("--min-pixels", o.min_segment_pixels,
                      "Evaluate car-frames with at least this many visible pixels")
      ->capture_default_str();
  command->add_option("--min-iou", o.min_iou,
                      "Per-track matching: 2D IoU needed to match a result box to the truth")
      ->capture_default_str();
  command->add_option("--match-distance", o.per_frame_distance,
                      "Per-frame matching and tracking figures: largest distance of a box's origin to the "
                      "true car's, m")
      ->capture_default_str();
  command->add_flag("--no-stereo", args->no_stereo, "Leave out the raw-stereo shape baseline");
  command->add_flag("--no-detections", args->no_detections, "Leave out the input-detection pose baseline");
  command->add_option("--threads", o.num_threads, "Worker threads (0 = all cores)")->capture_default_str();
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
    options.stereo_baseline = !args->no_stereo;
    options.detection_baseline = !args->no_detections;
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
