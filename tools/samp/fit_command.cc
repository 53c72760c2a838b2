// `samp fit`: sequence directories -> fitted shape and trajectory of every
// tracked car (docs/fitting.md).
#include <iostream>
#include <memory>

#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/pipeline/run_fit.h"
#include "libsamp/data/tracking.h"
#include "libsamp/viz/fit_pictures.h"
#include "tools/samp/commands.h"

#ifndef SAMP_DEFAULT_MODEL
#define SAMP_DEFAULT_MODEL ""
#endif

namespace samp::tools {

namespace {

// The tracker's options (docs/sequence_format.md, "Tracking by detection"):
// the noise model as comma-separated coefficients, then gates and rules.
void AddTrackerOptions(CLI::App* command, TrackerOptions* tracker) {
  auto coefficients = [command](const std::string& name, const std::string& help, std::vector<double*> targets) {
    std::string defaults;
    for (double* t : targets) defaults += (defaults.empty() ? "" : ",") + CLI::detail::to_string(*t);
    command
        ->add_option_function<std::vector<double>>(
            name,
            [targets, name](const std::vector<double>& values) {
              SAMP_CHECK(values.size() == targets.size())
                  << name << " takes " << targets.size() << " comma-separated values, got " << values.size();
              for (size_t i = 0; i < values.size(); ++i) *targets[i] = values[i];
            },
            help + " [" + defaults + "]")
        ->delimiter(',')
        ->expected(int(targets.size()));
  };
  coefficients("--tracker-along-sigma",
               "Tracker: detector std. dev. along the viewing ray a,b,c: a + b d + c d^2 (m, d = distance)",
               {&tracker->along_sigma_a, &tracker->along_sigma_b, &tracker->along_sigma_c});
  coefficients("--tracker-across-sigma", "Tracker: detector std. dev. across the ray a,b: a + b d (m)",
               {&tracker->across_sigma_a, &tracker->across_sigma_b});
  coefficients("--tracker-vertical-sigma", "Tracker: detector vertical std. dev. a,b: a + b d (m)",
               {&tracker->vertical_sigma_a, &tracker->vertical_sigma_b});
  command->add_option("--tracker-size-sigma", tracker->size_sigma,
                      "Tracker: std. dev. of each detected box dimension, m")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--tracker-yaw-sigma", tracker->yaw_sigma_deg,
                      "Tracker: std. dev. of the detected yaw modulo 180 deg, deg")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--tracker-acceleration-sigma", tracker->acceleration_sigma,
                      "Tracker: white acceleration noise of the constant-velocity model, m/s^2")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--tracker-gate", tracker->gate_chi2,
                      "Tracker: gate on the squared Mahalanobis distance of the ground-plane position (2 dof)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--tracker-yaw-gate", tracker->yaw_gate_deg,
                      "Tracker: largest axis difference (yaw modulo 180 deg) of a detection to its track, deg")
      ->capture_default_str();
  command->add_option("--tracker-confirm-hits", tracker->confirm_hits,
                      "Tracker: detections that confirm a new track")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--tracker-max-misses", tracker->max_misses,
                      "Tracker: a confirmed track ends after more consecutive missed frames")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--tracker-max-join-gap", tracker->max_join_gap,
                      "Tracker: fragments are joined across at most this many missed frames")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--tracker-join-gate", tracker->join_gate_chi2,
                      "Tracker: largest link cost of a join (squared Mahalanobis units)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_flag("--tracker-join,!--no-tracker-join", tracker->join_fragments,
                    "Tracker: join fragments whose constant-velocity fits agree")
      ->capture_default_str();
  command->add_flag("--tracker-swaps,!--no-tracker-swaps", tracker->resolve_switches,
                    "Tracker: swap the tails of two tracks where that resolves an identity switch")
      ->capture_default_str();
  command->add_flag("--tracker-robust-cues,!--no-tracker-robust-cues", tracker->robust_cues,
                    "Tracker: a single cue (box size, height or axis) outside its gate costs the gate's value "
                    "instead of starting a new track when position and motion agree")
      ->capture_default_str();
  command->add_option("--frame-rate", tracker->frame_rate_hz, "Frames per second of the sequences")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
}

}  // namespace

void RegisterFitCommand(CLI::App* app) {
  auto options = std::make_shared<RunFitOptions>();
  auto visuals = std::make_shared<FitVisualsOptions>();
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
                      "Sequence directory (docs/sequence_format.md); repeat for a batch")
      ->required();
  command->add_option("--out", o.output_dir,
                      "Output directory: written into a temporary folder beside it that replaces it as a "
                      "whole at the end; must be new, empty or an earlier samp fit output")
      ->required();
  command->add_option("--tracks", o.tracking_labels,
                      "KITTI tracking label file giving the tracks (frame track_id ...); repeat once "
                      "per --seq, in the same order: the way to plug in another tracker. Without it "
                      "detections/ are linked into tracks by samp's tracker (--tracker-* options)");
  command->add_flag("--single-frame", o.fit.single_frame,
                    "Single-frame mode (GCPR 2016): a shape per frame, no motion term");
  command->add_option("--em-iterations", o.fit.em_iterations,
                      "Hard-EM passes (re-associate points with the fitted trajectory, solve again)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--max-iterations", o.fit.max_iterations, "LM iterations per solve")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--linear-solver", o.fit.linear_solver,
                      "Ceres linear solver: sparse_normal_cholesky, dense_schur, iterative_schur, dense_qr")
      ->capture_default_str();
  command->add_option("--huber", o.fit.huber_threshold, "Huber threshold of the data term, in sigma_d")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_flag("--mixture-loss,!--huber-loss", o.fit.mixture_loss,
                    "Paper / ray-depth terms: the robust Gaussian + uniform mixture (threshold --outlier-threshold) "
                    "instead of Huber (docs/fitting.md)")
      ->capture_default_str();
  auto data_term = std::make_shared<std::string>(DataTermName(o.fit.data_term));
  command->add_option("--data-term", *data_term,
                      "Data term: disparity (each point's disparity vs that of the shape's visible surface on "
                      "its viewing ray, robust), paper (the SDF at the point, SAMP), ray-depth (the distance "
                      "along the viewing ray) (docs/fitting.md)")
      ->capture_default_str()
      ->check(CLI::IsMember({"disparity", "paper", "ray-depth"}));
  command->add_flag_callback("--ray-depth-inside", [data_term] { *data_term = "ray-depth"; },
                             "Same as --data-term ray-depth");
  auto weighting = std::make_shared<std::string>(DataWeightingName(o.fit.data_weighting));
  command->add_option("--weighting", *weighting,
                      "Data term against the priors: effective (each frame counts its effective number of "
                      "independent observations) or mean (the paper's (1/T) sum_t mean over points)")
      ->capture_default_str()
      ->check(CLI::IsMember({"effective", "mean"}));
  command->add_option("--max-solve-points", o.fit.max_solve_points_per_frame,
                      "At most this many of a frame's associated points enter each solve (an even subsample; "
                      "the data weight stays that of all of them); 0 = all")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--detection-size-sigma", o.fit.detection_size_sigma,
                      "Std. dev. of the detections' box sizes, which observe the shape's length, height and "
                      "width (docs/fitting.md, \"Detected size\"), m; 0 = off (the paper)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_flag("!--no-detection-position", o.fit.detection_position,
                    "Do not use the detections' box positions as observations of the poses (the paper: they only "
                    "initialise the fit); default: each counts with the tracker's detector noise model "
                    "(--tracker-*-sigma, docs/fitting.md, \"Detected position\")");
  command->add_option("--detection-correlation", o.fit.detection_correlation_frames,
                      "Frames over which the detector's errors are correlated (exp(-1/tau)); 0 = independent")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--correlation-area", o.fit.correlation_area_px,
                      "Image area over which stereo errors are correlated (effective weighting), px")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--outlier-threshold", o.fit.outlier_threshold,
                      "Mixture robustifier (disparity term, --mixture-loss): inlier/outlier threshold s_0, in sigma")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--association-radius", o.fit.association_radius,
                      "Initial association: points within this distance of the detection, m")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--sigma-disparity", o.sequence.observations.sigma_disparity_px,
                      "Disparity noise for sigma_d = d^2 sigma / (b f), px")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_flag("!--shared-points", o.sequence.observations.nearest_box_claims,
                    "Every track keeps every point of its 2D box (the paper); default: a point nearer to another "
                    "detection's 3D box of the same frame is that car's (docs/fitting.md, \"Association\")");
  command->add_option("--max-points", o.sequence.observations.max_points_per_frame,
                      "At most this many candidate points per frame (seeded subsample; 0 = all)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--standing-speed", o.fit.standing_speed,
                      "Below this speed the standing motion model is used, m/s")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--straight-yaw-rate", o.fit.straight_yaw_rate,
                      "Below this yaw rate the straight-line model is used, else the arc, rad/s")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--min-track-length", o.sequence.tracker.min_track_length,
                      "Tracks with fewer detections are dropped (1 keeps single detections, e.g. for "
                      "--single-frame)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  AddTrackerOptions(command, &o.sequence.tracker);
  command->add_flag("--self-calibrate,!--no-self-calibrate", o.self_calibrate,
                    "Estimate the detector's noise model from the sequences (robust linking, residuals of the "
                    "smoothed tracks, to a fixed point) and link and fit with it; writes OUT/detector_model.json "
                    "(docs/detector_calibration.md)")
      ->capture_default_str();
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
  command->callback([options, visuals, data_term, weighting] {
    options->fit.data_term = ParseDataTerm(*data_term);
    options->fit.data_weighting = ParseDataWeighting(*weighting);
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
