// `samp fit` as a library call: read sequence directories, link tracks, fit
// every track (joint SAMP or single-frame), write the outputs
// (docs/fitting.md, "Output"):
//   OUT/label_02/<seq>.txt    KITTI tracking result lines
//   OUT/meshes/track_<id>.ply, track_<id>_points.ply
//                             (OUT/meshes/<seq>/... when several sequences)
//   OUT/tracks.json           per sequence and track: shape, poses, costs
//   OUT/config.json           effective options and model file
// Sequences and tracks run in parallel (TBB); a sequence or track that fails
// is reported in the summary and skipped, the others complete. All files are
// written atomically; a failed sequence writes no label file.
#pragma once

#include <string>
#include <vector>

#include "libsamp/fit/fitter.h"
#include "libsamp/data/sequence.h"

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
  std::vector<std::string> track_failures;  // "track <id>: message"
  double seconds = 0.0;
};

struct RunFitSummary {
  std::vector<SequenceFitResult> sequences;
  int num_sequences_failed = 0;
  int num_tracks_fitted = 0;
  int num_tracks_failed = 0;
  double seconds = 0.0;
  std::string BriefReport() const;
};

// Throws samp::Error when the options are invalid or the model does not load;
// failures of single sequences or tracks are in the summary.
RunFitSummary RunFit(const RunFitOptions& options);

}  // namespace samp
