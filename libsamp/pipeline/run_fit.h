// `samp fit` as a library call: read sequence directories, link tracks, fit
// every track (joint SAMP or single-frame), write the outputs
// (docs/fitting.md, "Output"):
//   OUT/label_02/<seq>.txt    KITTI tracking result lines
//   OUT/meshes/track_<id>.ply, track_<id>_points.ply
//                             (OUT/meshes/<seq>/... when several sequences)
//   OUT/tracks.json           per sequence and track: shape, poses, costs;
//                             the run's detector model ("detector_model")
//   OUT/config.json           effective options and model file
//   OUT/detector_model.json   the run's detector model, when it used one,
//                             and its plot detector_model.png (detector_plot)
// Sequences and tracks run in parallel (TBB); a sequence or track that fails
// is reported in the summary and skipped, the others complete. A failed
// sequence writes no label file.
//
// OUT is written completely or not at all (core/atomic_file.h StagedFolder;
// a failed run, RunFitSummary::failure, never replaces an earlier output):
// every file goes into a temporary folder beside OUT, which replaces OUT as a
// whole at the end, so no file of an earlier run (label_02/, meshes/,
// pictures/, index.html) survives into a new one. A run that throws (bad
// options, a model that does not load, a write error) or is interrupted leaves
// OUT as it was. OUT may be a new or empty folder or the output of an earlier
// samp run (its marker file .samp_run lists every file in it:
// CheckReplaceableOutputFolder); any other folder (the foreign files are
// listed), a file, a folder that holds an input (a --seq, --tracks or model
// file; by path and by device and inode) or the current folder is refused
// before anything is read. Two sequences whose
// outputs would share a name (label_02/<seq>.txt) are refused too.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "libsamp/data/detector_noise.h"
#include "libsamp/data/sequence.h"
#include "libsamp/fit/fitter.h"

namespace samp {

struct RunFitOptions {
  // Shape model file (.vdb).
  std::string model_path;
  // Sequence directories (layout in docs/sequence_format.md).
  std::vector<std::string> sequences;
  // Optional KITTI tracking label files, empty or one per sequence (same order).
  std::vector<std::string> tracking_labels;
  // Output directory (created).
  std::string output_dir;
  FitOptions fit;
  SequenceOptions sequence;
  // Worker threads for sequences and tracks (TBB); 0 = all cores.
  int num_threads = 0;
  // Write meshes and aligned points.
  bool write_meshes = true;
  // Only link the detections into tracks and write their detections as the
  // labels (label_02/<seq>.txt, tracks.json with the tracking summaries,
  // config.json): no model, no fit. The labels can be evaluated (pose and
  // tracking) or given back as --tracks.
  bool link_only = false;
  // Called with the temporary output folder (holding every file of the run,
  // tracks.json and config.json included) before it replaces output_dir, when
  // the run did not fail (RunFitSummary::failure empty): what it writes there
  // is part of the output (`samp fit --pictures --html`). If it throws,
  // output_dir stays as it was. Not written to config.json.
  std::function<void(const std::string& folder)> before_commit;
  // Detector self-calibration (docs/detector_calibration.md): link every
  // sequence with robust cues, estimate the detector's noise model from the
  // tracks of all sequences (pooled), re-link with it to a fixed point, then
  // link and fit with the estimate: the tracker's sigmas and the fit's
  // detection size sigma (unless 0 = off) and position covariance come from
  // it. Then the box convention (detected box minus the shape's extent, and
  // an along-ray offset; calibration.box, docs/detector_calibration.md "Box
  // conventions"): the near, well-observed cars are fitted to their points
  // alone, compared with their detections, and every car is fitted with the
  // estimate (unless calibration.estimate_box_convention is false or the fit
  // options give a bias). The estimate goes to OUT/detector_model.json,
  // tracks.json ("detector_model") and the summary. On by default (`samp fit
  // --no-self-calibrate`: the tracker's fixed sigmas, no box convention).
  bool self_calibrate = true;
  CalibrationOptions calibration;
  // A detector model file (`samp calibrate-detector`, data/detector_noise.h)
  // used instead of the tracker's and the fit's detector sigmas and instead of
  // self-calibration; its box convention, when it has one, is applied too.
  std::string detector_model_path;
  // Draw the detector model the run used (self-calibrated or read) as
  // OUT/detector_model.png beside detector_model.json, through
  // draw_detector_model (without it nothing is drawn). Written to config.json
  // only when off.
  bool detector_plot = true;
  // Draws a detector model as a PNG file at `path` (`samp fit` and the Python
  // bindings set viz/detector_noise_plot.h's WriteDetectorNoisePlot: the
  // pipeline itself does not draw). Called with a path in the temporary
  // output folder when detector_plot is on and the run used a detector model;
  // if it throws, the run throws and output_dir stays as it was. Not written
  // to config.json.
  std::function<void(const std::string& path, const DetectorNoiseModel& model)> draw_detector_model;

  // Throws samp::Error naming the field and the rule it broke.
  void Check() const;
};

struct SequenceFitResult {
  std::string directory;
  std::string name;
  bool ok = false;                // read and linked (tracks may still fail)
  std::string error;              // why the sequence failed
  SequenceSummary input;
  int num_tracks = 0;
  int num_fitted = 0;
  int num_at_grid_limit = 0;      // fitted tracks whose shape fills the model's grid (GridLimitsReached)
  std::vector<std::string> track_failures;  // "track <id>: message"
  double seconds = 0.0;         // the whole sequence: input.seconds_{frames,tracking}, the two below, the rest
  double seconds_fit = 0.0;     // the tracks' fits
  double seconds_output = 0.0;  // labels, meshes and records of the fitted tracks
};

struct RunFitSummary {
  std::vector<SequenceFitResult> sequences;
  int num_sequences_failed = 0;
  int num_tracks_fitted = 0;
  int num_tracks_failed = 0;
  // Why the run failed (`samp fit` then exits 1): a sequence failed (one of a
  // batch is enough), or no track was fitted although the input had
  // detections (every track failed or was dropped). Empty otherwise. A failed
  // run is written into a new or empty output folder (its tracks.json says
  // why) but never replaces an earlier run's output (kept_previous_output).
  std::string failure;
  bool replaced_previous_output = false;  // output_dir held an earlier run, now replaced
  bool kept_previous_output = false;      // the run failed and output_dir keeps the earlier run
  // The detector model the run used (self-calibrated or read), when any.
  bool detector_model_used = false;
  DetectorNoiseModel detector_model;
  std::string calibration_report;  // CalibrationResult::BriefReport, or where the model was read
  double seconds_calibration = 0.0;  // self-calibration (detector noise and box convention), before the sequences
  double seconds = 0.0;
  std::string BriefReport() const;
};

// Throws samp::Error when the options are invalid, the output folder may not
// be replaced, two sequences have the same name, the model does not load or
// the output cannot be written (output_dir then stays as it was); failures of
// single sequences or tracks are in the summary.
RunFitSummary RunFit(const RunFitOptions& options);

// The name of a sequence's outputs (label_02/<name>.txt, meshes/<name>/):
// the stem of its calibration file (data/sequence.h ListSequence), or the
// folder's name when the folder cannot be listed.
std::string SequenceOutputName(const std::string& directory);

}  // namespace samp
