// `samp eval`: the paper's evaluation (Section 4) of fitted tracks on
// synthetic sequences with ground truth (docs/evaluation.md).
//
// For every ground-truth car and frame (gt/label_02/<seq>.txt) whose object-map
// segment has enough pixels:
//  - true points: gt/depth inside the segment, back-projected;
//  - per result with meshes: the result label of that frame matched to the car
//    (greedy 2D IoU of the projected 3D boxes), its mesh rendered into the left
//    camera at the label's pose, depth buffer read at the segment's pixels;
//  - the "stereo" baseline: the input disparity inside the segment;
//  - the "detections" baseline (pose only): SEQ/detections matched the same way.
// Shape: accuracy, completeness and F1 for a sweep of tau; pose: translation
// error and absolute yaw error in distance windows. Shape and pose statistics
// are taken over the car-frames that every compared method matched (the
// common set); each method's coverage is reported too.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace samp {

struct EvalOptions {
  // Synthetic sequence directories (with gt/).
  std::vector<std::string> sequences;
  // Results to compare: (name, folder of a `samp fit` output). The folder holds
  // label_02/<seq>.txt and meshes/track_<id>.ply (or <seq>/label_02/..., <seq>/meshes/...).
  std::vector<std::pair<std::string, std::string>> results;
  // Output folder for the tables (Markdown, CSV, JSON) and the plots (PNG).
  std::string output_folder;
  // Thresholds tau of the shape sweep (metres, increasing) and the headline one (in the sweep).
  std::vector<double> taus = {0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5};
  double headline_tau = 0.2;
  // Width of the distance windows of the pose statistics, metres.
  double distance_window = 20.0;
  // Car-frames whose object-map segment has fewer pixels are not evaluated.
  int min_segment_pixels = 100;
  // A result/detection box matches a ground-truth box when their 2D IoU is at least this.
  double min_iou = 0.3;
  // Include the raw-stereo shape baseline and the input-detection pose baseline.
  bool stereo_baseline = true;
  bool detection_baseline = true;
  // Threads for the per-sequence work (0 = all cores).
  int num_threads = 0;

  void Check() const;
  std::string ToJson() const;
};

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

struct EvalSummary {
  std::vector<double> taus;
  double headline_tau = 0.2;
  int num_sequences = 0;
  int num_gt_car_frames = 0;   // with a large enough segment
  int num_gt_tracks = 0;
  std::vector<MethodShapeResult> shape;
  std::vector<MethodPoseResult> pose;
  std::string markdown;        // the tables (also written to results.md)
  double seconds = 0.0;
  std::string BriefReport() const;
};

// Evaluates and writes OUT/results.md, results.json, shape.csv, pose.csv,
// per_object.csv and the plots f1_vs_tau.png, accuracy_vs_tau.png,
// completeness_vs_tau.png, translation_vs_distance.png, yaw_vs_distance.png.
// Throws samp::Error naming the file on missing or malformed input.
EvalSummary Evaluate(const EvalOptions& options);

}  // namespace samp
