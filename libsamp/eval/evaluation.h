// `samp eval`: the paper's evaluation (Section 4) of fitted tracks on
// synthetic sequences with ground truth (docs/evaluation.md).
//
// For every ground-truth car and frame (gt/label_02/<seq>.txt) whose object-map
// segment has enough pixels:
//  - true points: gt/depth inside the segment, back-projected;
//  - per result with meshes: the result label of that frame matched to the car,
//    its mesh rendered into the left camera at the label's pose, depth buffer
//    read at the segment's pixels. Two matchings, both reported: per track
//    (each true car gets the one output track sharing most frames with it,
//    frames matched by greedy 2D IoU of the projected 3D boxes; a fragmented or
//    swapped track costs) and per frame (each true car-frame gets the nearest
//    box of any track within per_frame_distance; abstracts from tracking);
//  - the "stereo" baseline: the input disparity inside the segment;
//  - the "detections" baseline (pose only): SEQ/detections matched the same way
//    (no track ids: per track = per-frame IoU).
// Shape: accuracy, completeness and F1 for a sweep of tau; pose: translation
// error and absolute yaw error in distance windows. Shape and pose statistics
// are taken over the car-frames that every compared method matched (the
// common set); each method's coverage is reported too. Tracking: CLEAR-MOT
// figures of each result (per-frame matching). Per-car diagnostics: offsets
// of the origin along and across the viewing ray, box sizes, F1.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "libsamp/eval/eval_options.h"
#include "libsamp/eval/metrics.h"

namespace samp {

// Per method: aggregated scores over the common set.
struct MethodShapeResult {
  std::string method;
  std::vector<double> accuracy, completeness, f1;  // mean over car-frames, one per tau
  int num_evaluated = 0;                           // car-frames in the common set
  int num_matched = 0;                             // car-frames this method matched
};

struct PoseWindow {
  double min_distance = 0.0, max_distance = 0.0;
  int count = 0;
  double translation_mean = 0.0, translation_median = 0.0;  // m
  double yaw_mean_deg = 0.0, yaw_median_deg = 0.0;
};

struct MethodPoseResult {
  std::string method;
  std::vector<PoseWindow> windows;  // consecutive distance windows
  PoseWindow all;                   // all distances
  PoseWindow beyond_first;          // distances >= the first window (e.g. beyond 20 m)
  int num_matched = 0;
};

// CLEAR-MOT figures of one result (per-frame matching).
struct MethodTrackingResult {
  std::string method;
  TrackingCounts counts;
};

// Medians of the per-car diagnostics over one distance band (per-frame matching).
struct DiagnosticsBand {
  std::string method;
  double min_distance = 0.0, max_distance = 0.0;
  int count = 0;
  double along_ray_offset = 0.0;     // median, signed (+ = farther than the truth), m
  double abs_lateral_offset = 0.0;   // median |across the ray|, m
  double abs_vertical_offset = 0.0;  // median |vertical|, m
  Eigen::Vector3d size_error = Eigen::Vector3d::Zero();  // median estimated - true h, w, l, m
  double f1 = 0.0;                   // median F1 at the headline tau (shape methods)
  int num_shape = 0;                 // car-frames with a shape score
};

struct EvalSummary {
  std::vector<double> taus;
  double headline_tau = 0.2;
  int num_sequences = 0;
  int num_gt_car_frames = 0;   // with a large enough segment
  int num_gt_tracks = 0;
  // Per-track matching (each true car gets one output track).
  std::vector<MethodShapeResult> shape;
  std::vector<MethodPoseResult> pose;
  // Per-frame matching (each true car-frame gets the nearest box of any track).
  std::vector<MethodShapeResult> shape_per_frame;
  std::vector<MethodPoseResult> pose_per_frame;
  // Tracking figures of each result, and the diagnostics by distance band.
  std::vector<MethodTrackingResult> tracking;
  std::vector<DiagnosticsBand> diagnostics;
  std::string markdown;        // the tables (also written to results.md)
  double seconds = 0.0;
  // The index of headline_tau in taus.
  size_t HeadlineIndex() const;
  std::string BriefReport() const;
};

// One method's view of one ground-truth car-frame under one matching.
struct MethodCarFrame {
  bool matched = false;
  bool has_shape = false;
  int output_track = -1;
  double translation_error = 0.0, yaw_error_deg = 0.0;
  // Offset of the estimated origin from the true one in the camera: along the
  // horizontal viewing ray to the true origin (+ = farther), across it (+ =
  // right), vertically (+ = lower, camera y).
  double along_ray_offset = 0.0, lateral_offset = 0.0, vertical_offset = 0.0;
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  // estimated h, w, l
  int num_estimated_points = 0;
  std::vector<ShapeScores> scores;  // per tau
};

// One ground-truth car-frame with a large enough segment, and every method's
// view of it under each matching (methods[k][m]: matching k, method m).
struct CarFrameRecord {
  std::string sequence;
  int track_id = 0, frame = 0;
  double distance = 0.0;
  int segment_pixels = 0;
  int num_true_points = 0;
  Eigen::Vector3d true_size = Eigen::Vector3d::Zero();  // h, w, l
  std::vector<MethodCarFrame> methods[kNumMatchings];
};

// What an evaluation computes, before anything is written: the summary (its
// markdown and seconds not yet set) and the car-frame records it aggregates.
struct EvalResults {
  EvalSummary summary;
  std::vector<EvalMethod> methods;      // the baselines, then the results in the given order
  std::vector<CarFrameRecord> records;  // every evaluated car-frame, sequence by sequence
  int num_windows = 1;                  // distance windows of the pose statistics
  // The sequences have no ground-truth maps (KITTI tracking's layout): the
  // evaluated car-frames are chosen by EvalOptions' box height, occlusion and
  // truncation, and there are no shape figures.
  bool without_maps = false;
};

// Reads the sequences and results and aggregates the scores; writes nothing.
// Throws samp::Error naming the file on missing or malformed input.
EvalResults ComputeEvaluation(const EvalOptions& options);

// ComputeEvaluation, then the tables and plots (eval/eval_report.h): writes OUT/results.md, results.json, shape.csv, pose.csv,
// per_object.csv, tracking.csv, per_car.csv and the plots f1_vs_tau.png, accuracy_vs_tau.png,
// completeness_vs_tau.png, translation_vs_distance.png, yaw_vs_distance.png.
// Throws samp::Error naming the file on missing or malformed input.
EvalSummary Evaluate(const EvalOptions& options);

}  // namespace samp
