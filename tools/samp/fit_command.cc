// `samp fit`: sequence directories -> fitted shape and trajectory of every
// tracked car (docs/fitting.md).
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/pipeline/run_fit.h"
#include "libsamp/pipeline/run_fit_option_table.h"
#include "libsamp/data/calibration_option_table.h"
#include "libsamp/data/kitti_tracking.h"
#include "libsamp/data/observation_option_table.h"
#include "libsamp/data/sequence.h"
#include "libsamp/data/sequence_option_table.h"
#include "libsamp/data/tracker_option_table.h"
#include "libsamp/fit/fit_option_table.h"
#include "libsamp/viz/detector_noise_plot.h"
#include "libsamp/viz/fit_pictures.h"
#include "tools/samp/commands.h"
#include "tools/samp/option_cli.h"

#ifndef SAMP_DEFAULT_MODEL
#define SAMP_DEFAULT_MODEL ""
#endif

namespace samp::tools {
namespace {

// Where the inputs are, besides --seq: KITTI tracking sequences and frames.
// Command-line plumbing only, hence registered here and not on a table: the
// callback turns them into RunFitOptions' sequences and SequenceOptions'
// frame range, which config.json holds.
struct InputSource {
  std::string kitti_root;
  std::string kitti_stereo_root;
  std::string kitti_sequences = "all";
  std::string frames;
};

// --kitti-tracking, --kitti-stereo, --sequence and --frames.
void AddInputSourceOptions(CLI::App* command, InputSource* source, const std::string& input_group) {
  command->add_option("--kitti-tracking", source->kitti_root,
                      "KITTI tracking folder in its own layout (training/ or testing/: image_02, image_03, calib, "
                      "oxts); ego poses from oxts/")
      ->check(CLI::ExistingDirectory)
      ->group(input_group);
  command->add_option("--kitti-stereo", source->kitti_stereo_root,
                      "KITTI stereo 2015 (multiview) folder in its own layout (image_2/<seq>_<ff>.png, image_3, "
                      "calib_cam_to_cam/<seq>.txt); no ego poses: static camera")
      ->check(CLI::ExistingDirectory)
      ->group(input_group);
  command->add_option("--sequence", source->kitti_sequences,
                      "With --kitti-tracking or --kitti-stereo: sequences to fit, comma-separated (0004,0011; "
                      "000046) or all")
      ->capture_default_str()
      ->group(input_group);
  command->add_option("--frames", source->frames, "Fit only frames FIRST-LAST (e.g. 100-300) of each sequence")
      ->group(input_group);
}

// The callback of `samp fit`: the input source into the options, the run, the pictures and viewer.
void RunFitCommand(const std::shared_ptr<RunFitOptions>& options, const std::shared_ptr<FitVisualsOptions>& visuals,
                   const InputSource& source, const CLI::App& command) {
  SAMP_CHECK(command.count("--sequence") == 0 || !source.kitti_root.empty() || !source.kitti_stereo_root.empty())
      << "--sequence names sequences of --kitti-tracking or --kitti-stereo; give one of them (or --seq)";
  if (!source.kitti_root.empty()) {
    for (const std::string& folder : KittiTrackingSequenceFolders(source.kitti_root, source.kitti_sequences))
      options->sequences.push_back(folder);
  }
  if (!source.kitti_stereo_root.empty()) {
    for (const std::string& file : KittiStereoSequences(source.kitti_stereo_root, source.kitti_sequences))
      options->sequences.push_back(file);
  }
  if (options->sequences.empty()) throw CLI::RequiredError("--seq, --kitti-tracking or --kitti-stereo");
  if (!source.frames.empty()) ParseFrameRange(source.frames, &options->sequence);
  std::error_code error;
  SAMP_CHECK(options->sequence.detections_path.empty() || options->sequences.size() == 1 ||
             std::filesystem::is_directory(options->sequence.detections_path, error))
      << "--detections " << options->sequence.detections_path << " is a file, but " << options->sequences.size()
      << " sequences are fitted: give a folder with <seq>.txt per sequence";
  SAMP_CHECK(options->link_only || !options->model_path.empty())
      << "no --model given and this build has no default model";
  SAMP_CHECK(!(options->link_only && (visuals->pictures || visuals->html)))
      << "--link-only fits nothing: --pictures and --html need fitted shapes";
  // Pictures and viewer go into the run's temporary output folder, so that
  // they replace the earlier run's together with everything else.
  std::string visuals_report;
  if (visuals->pictures || visuals->html) {
    options->before_commit = [visuals, &visuals_report](const std::string& folder) {
      FitVisualsOptions v = *visuals;
      v.output_dir = folder;
      visuals_report = WriteFitVisuals(v).BriefReport();
      // Name the files where they will be after the rename.
      for (size_t at = visuals_report.find(folder); at != std::string::npos;
           at = visuals_report.find(folder, at + visuals->output_dir.size())) {
        visuals_report.replace(at, folder.size(), visuals->output_dir);
      }
    };
    visuals->output_dir = options->output_dir;
  }
  // OUT/detector_model.png: the plot `samp calibrate-detector` draws.
  options->draw_detector_model = [](const std::string& path, const DetectorNoiseModel& model) {
    WriteDetectorNoisePlot(path, model);
  };
  const RunFitSummary summary = RunFit(*options);
  std::cout << summary.BriefReport() << std::endl;
  if (summary.kept_previous_output) {
    SAMP_THROW() << summary.failure << "; " << options->output_dir << " keeps the earlier run's output";
  }
  std::cout << "wrote " << options->output_dir << std::endl;
  if (!summary.failure.empty()) SAMP_THROW() << summary.failure;
  if (!visuals_report.empty()) std::cout << visuals_report << std::endl;
}

}  // namespace

void RegisterFitCommand(CLI::App* app) {
  auto options = std::make_shared<RunFitOptions>();
  auto visuals = std::make_shared<FitVisualsOptions>();
  auto source = std::make_shared<InputSource>();
  visuals->pictures = visuals->html = false;
  RunFitOptions& o = *options;
  o.model_path = SAMP_DEFAULT_MODEL;
  CLI::App* command = app->add_subcommand(
      "fit",
      "Fit shape (PCA SDF manifold) and trajectory of every tracked car in stereo sequences,\n"
      "with shape and motion priors (SAMP). Writes OUT/label_02/<seq>.txt (KITTI tracking\n"
      "results), OUT/meshes/track_<id>.ply (+ _points.ply), OUT/tracks.json, OUT/config.json and\n"
      "the detector model OUT/detector_model.json with its plot detector_model.png.\n"
      "A sequence or track that fails is reported and skipped; OUT holds this run only.\n"
      "See docs/fitting.md.");
  // RunFitOptions' own fields from its table (pipeline/run_fit_option_table.h),
  // each at its place among the other options.
  const std::vector<OptionBinding> run = RunFitOptionTable().Bind(&o);
  const std::string run_group = "Options";
  AddTableOptions(command, Only(run, {"model", "sequences"}), "", run_group);
  const std::string input_group = "Input (docs/sequence_format.md)";
  AddInputSourceOptions(command, source.get(), input_group);
  // SequenceOptions' own options (--detections, --detection-format, --min-score, --types): its table
  // (data/sequence_option_table.h).
  AddTableOptions(command, SequenceOptionTable().Bind(&o.sequence), "", input_group);
  AddTableOptions(command, Only(run, {"output_dir", "tracking_labels"}), "", run_group);
  // FitOptions (with its MotionNoise) and TrackerOptions: every field from
  // their tables (fit/fit_option_table.h, data/tracker_option_table.h).
  const std::string fit_group = "Fit (FitOptions; docs/fitting.md, \"Options\")";
  AddTableOptions(command, FitOptionTable().Bind(&o.fit), "", fit_group);
  const std::string tracker_group = "Tracker (TrackerOptions; docs/fitting.md, \"Tracker\")";
  const std::vector<OptionBinding> tracker = TrackerOptionTable().Bind(&o.sequence.tracker);
  AddTableOptions(command, tracker, "tracker-", tracker_group);
  AddListOption(command, tracker, "--tracker-along-sigma", {"along_sigma_a", "along_sigma_b", "along_sigma_c"},
                "Detector std. dev. along the viewing ray a,b,c: a + b d + c d^2 (m, d = distance)", tracker_group);
  AddListOption(command, tracker, "--tracker-across-sigma", {"across_sigma_a", "across_sigma_b"},
                "Detector std. dev. across the ray a,b: a + b d (m)", tracker_group);
  AddListOption(command, tracker, "--tracker-vertical-sigma", {"vertical_sigma_a", "vertical_sigma_b"},
                "Detector vertical std. dev. a,b: a + b d (m)", tracker_group);
  AddHelpOptions(command, {{"markdown", FitOptionTable().Describe(), ""},
                           {"tracker-markdown", TrackerOptionTable().Describe(), "tracker-"},
                           {"observation-markdown", ObservationOptionTable().Describe(), ""},
                           {"stereo-markdown", StereoOptionTable().Describe(), "stereo-"},
                           {"road-markdown", RoadPlaneOptionTable().Describe(), "road-"},
                           {"calibration-markdown", CalibrationOptionTable().Describe(), "calibration-"},
                           {"input-markdown", SequenceOptionTable().Describe(), ""},
                           {"run-markdown", RunFitOptionTable().Describe(), ""}});
  const std::string observation_group = "Candidate points (ObservationOptions; docs/fitting.md, \"Association\")";
  AddTableOptions(command, ObservationOptionTable().Bind(&o.sequence.observations), "", observation_group);
  AddTableOptions(command, StereoOptionTable().Bind(&o.sequence.stereo), "stereo-",
                  "Disparity of frames without disparity/ (StereoOptions; docs/sequence_format.md, \"Stereo\")");
  AddTableOptions(command, RoadPlaneOptionTable().Bind(&o.sequence.road_plane), "road-",
                  "Road plane of frames without planes/ (RoadPlaneOptions; docs/sequence_format.md, \"Road plane\")");
  AddTableOptions(command, Only(run, {"self_calibrate"}), "", run_group);
  const std::string calibration_group =
      "Self-calibration (CalibrationOptions; docs/detector_calibration.md, \"Options\")";
  AddTableOptions(command, CalibrationOptionTable().Bind(&o.calibration), "calibration-", calibration_group);
  AddTableOptions(command, Only(run, {"detector_model", "detector_plot", "link_only", "write_meshes"}), "", run_group);
  command->add_flag("--pictures", visuals->pictures,
                    "After the fit, draw PNG pictures per track and sequence into OUT/pictures/ "
                    "(mesh in the image, bird's-eye before/after, shape strip; docs/fitting.md)");
  command->add_flag("--html", visuals->html,
                    "After the fit, write the interactive viewer OUT/index.html (same as `samp view OUT`)");
  AddTableOptions(command, Only(run, {"num_threads"}), "", run_group);
  AddCommonOptions(command);
  command->callback([options, visuals, source, command] { RunFitCommand(options, visuals, *source, *command); });
}

}  // namespace samp::tools
