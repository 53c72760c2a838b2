// `samp fit`: sequence directories -> fitted shape and trajectory of every
// tracked car (docs/fitting.md).
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>

#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/pipeline/run_fit.h"
#include "libsamp/data/calibration_option_table.h"
#include "libsamp/data/kitti_tracking.h"
#include "libsamp/data/observation_option_table.h"
#include "libsamp/data/sequence.h"
#include "libsamp/data/sequence_option_table.h"
#include "libsamp/data/tracker_option_table.h"
#include "libsamp/fit/fit_option_table.h"
#include "libsamp/viz/fit_pictures.h"
#include "tools/samp/commands.h"
#include "tools/samp/option_cli.h"

#ifndef SAMP_DEFAULT_MODEL
#define SAMP_DEFAULT_MODEL ""
#endif

namespace samp::tools {
namespace {

// Where the inputs are, besides --seq: KITTI tracking sequences, frames, detections.
struct InputSource {
  std::string kitti_root;
  std::string kitti_stereo_root;
  std::string kitti_sequences = "all";
  std::string frames;
  std::string object_types;
};

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
      "results), OUT/meshes/track_<id>.ply (+ _points.ply), OUT/tracks.json and OUT/config.json.\n"
      "A sequence or track that fails is reported and skipped; OUT holds this run only.\n"
      "See docs/fitting.md.");
  command->add_option("--model", o.model_path, "Shape model file (.vdb); default: the shipped model")
      ->capture_default_str();
  command->add_option("--seq", o.sequences,
                      "Sequence directory (docs/sequence_format.md; samp's layout, a KITTI tracking "
                      "ROOT/image_02/<seq> or a KITTI stereo ROOT/calib_cam_to_cam/<seq>.txt); repeat for a batch");
  const std::string input_group = "Input (docs/sequence_format.md)";
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
  // SequenceOptions' own options (--detections, --detection-format, --min-score): its table
  // (data/sequence_option_table.h).
  AddTableOptions(command, SequenceOptionTable().Bind(&o.sequence), "", input_group);
  command->add_option("--types", source->object_types,
                      "Object types used, comma-separated, case-insensitive (default Car)")
      ->group(input_group);
  command->add_option("--out", o.output_dir,
                      "Output directory: written into a temporary folder beside it that replaces it as a "
                      "whole at the end; must be new, empty or an earlier samp fit output")
      ->required();
  command->add_option("--tracks", o.tracking_labels,
                      "KITTI tracking label file giving the tracks (frame track_id ...); repeat once "
                      "per --seq, in the same order: the way to plug in another tracker. Without it "
                      "detections/ are linked into tracks by samp's tracker (--tracker-* options)");
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
                           {"input-markdown", SequenceOptionTable().Describe(), ""}});
  const std::string observation_group = "Candidate points (ObservationOptions; docs/fitting.md, \"Association\")";
  AddTableOptions(command, ObservationOptionTable().Bind(&o.sequence.observations), "", observation_group);
  AddTableOptions(command, StereoOptionTable().Bind(&o.sequence.stereo), "stereo-",
                  "Disparity of frames without disparity/ (StereoOptions; docs/sequence_format.md, \"Stereo\")");
  AddTableOptions(command, RoadPlaneOptionTable().Bind(&o.sequence.road_plane), "road-",
                  "Road plane of frames without planes/ (RoadPlaneOptions; docs/sequence_format.md, \"Road plane\")");
  command->add_flag("--self-calibrate,!--no-self-calibrate", o.self_calibrate,
                    "Estimate the detector's noise model from the sequences (robust linking, residuals of the "
                    "smoothed tracks, to a fixed point) and link and fit with it; writes OUT/detector_model.json "
                    "(docs/detector_calibration.md)")
      ->capture_default_str();
  const std::string calibration_group =
      "Self-calibration (CalibrationOptions; docs/detector_calibration.md, \"Options\")";
  AddTableOptions(command, CalibrationOptionTable().Bind(&o.calibration), "calibration-", calibration_group);
  command->add_option("--calibration-bin-edges", o.calibration.noise.bin_edges,
                      "Distance bin edges of the noise estimate, m, increasing, comma-separated (the last bin is open)")
      ->delimiter(',')
      ->capture_default_str()
      ->group(calibration_group);
  command->add_option("--detector-model", o.detector_model_path,
                      "A detector model JSON (samp calibrate-detector) giving the tracker's and the fit's "
                      "detector sigmas (instead of --tracker-*-sigma and --self-calibrate)")
      ->check(CLI::ExistingFile);
  command->add_flag("--link-only", o.link_only,
                    "Only link detections/ into tracks and write the tracked detections as "
                    "label_02/<seq>.txt (no model, no fit; for samp eval's tracking figures or --tracks)");
  command->add_flag_callback("--no-meshes", [options] { options->write_meshes = false; },
                    "Do not write meshes/ (PLY surfaces and aligned points)");
  command->add_flag("--pictures", visuals->pictures,
                    "After the fit, draw PNG pictures per track and sequence into OUT/pictures/ "
                    "(mesh in the image, bird's-eye before/after, shape strip; docs/fitting.md)");
  command->add_flag("--html", visuals->html,
                    "After the fit, write the interactive viewer OUT/index.html (same as `samp view OUT`)");
  command->add_option("--threads", o.num_threads, "Worker threads for sequences and tracks (0 = all cores)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  AddCommonOptions(command);
  command->callback([options, visuals, source, command] {
    SAMP_CHECK(command->count("--sequence") == 0 || !source->kitti_root.empty() || !source->kitti_stereo_root.empty())
        << "--sequence names sequences of --kitti-tracking or --kitti-stereo; give one of them (or --seq)";
    if (!source->kitti_root.empty()) {
      for (const std::string& folder : KittiTrackingSequenceFolders(source->kitti_root, source->kitti_sequences))
        options->sequences.push_back(folder);
    }
    if (!source->kitti_stereo_root.empty()) {
      for (const std::string& file : KittiStereoSequences(source->kitti_stereo_root, source->kitti_sequences))
        options->sequences.push_back(file);
    }
    if (options->sequences.empty()) throw CLI::RequiredError("--seq, --kitti-tracking or --kitti-stereo");
    if (!source->frames.empty()) ParseFrameRange(source->frames, &options->sequence);
    if (!source->object_types.empty()) {
      options->sequence.object_types.clear();
      std::stringstream list(source->object_types);
      for (std::string type; std::getline(list, type, ',');)
        if (!type.empty()) options->sequence.object_types.push_back(type);
    }
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
    const RunFitSummary summary = RunFit(*options);
    std::cout << summary.BriefReport() << std::endl;
    if (summary.kept_previous_output) {
      SAMP_THROW() << summary.failure << "; " << options->output_dir << " keeps the earlier run's output";
    }
    std::cout << "wrote " << options->output_dir << std::endl;
    if (!summary.failure.empty()) SAMP_THROW() << summary.failure;
    if (!visuals_report.empty()) std::cout << visuals_report << std::endl;
  });
}

}  // namespace samp::tools
