// What the evaluation's stages (eval_inputs.h, matching.h) share with its
// interface (evaluation.h): the options, the two matchings and the compared
// methods. Kept apart from evaluation.h so that the stages include downwards
// only.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace samp {

struct EvalOptions {
  // Synthetic sequence directories (with gt/), or sequences of KITTI tracking's
  // layout (ROOT/image_02/<seq>, ground truth ROOT/label_02/<seq>.txt): those
  // have no depth or object maps and are evaluated for pose and tracking only.
  // The two kinds are not mixed in one evaluation.
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
  // Per-track matching: a result/detection box matches a ground-truth box when
  // their 2D IoU is at least this.
  double min_iou = 0.3;
  // Per-frame matching and the tracking figures: a box matches a true car
  // when their origins are at most this far apart, metres.
  double per_frame_distance = 2.0;
  // Include the raw-stereo shape baseline and the input-detection pose baseline.
  bool stereo_baseline = true;
  bool detection_baseline = true;
  // KITTI tracking's layout: a true car is evaluated when its 2D box is at
  // least this tall, its occlusion at most and its truncation at most these
  // (KITTI's "moderate" difficulty: 25 px, partly occluded, 30 %); the others
  // are ignored as under min_segment_pixels.
  double min_box_height_px = 25.0;
  int max_occlusion = 1;
  double max_truncation = 0.3;
  // KITTI tracking's layout: the detections of the detection baseline, a file
  // (one sequence) or a folder with <seq>.txt per sequence, in any format of
  // `samp fit --detections` (docs/sequence_format.md); empty: no detection
  // baseline for such sequences.
  std::string detections_path;
  // Threads for the per-sequence work (0 = all cores).
  int num_threads = 0;

  void Check() const;
  std::string ToJson() const;
};

// The two matchings (docs/evaluation.md): per track, each true car gets one
// output track for the whole sequence; per frame, each true car at each frame
// gets the nearest output box of any track within per_frame_distance.
constexpr int kPerTrack = 0, kPerFrame = 1, kNumMatchings = 2;

// A compared method: a baseline ("stereo", "detections") or a result folder.
struct EvalMethod {
  std::string name, folder;
  bool shape = false, pose = false;  // evaluated for shape (has surfaces), for pose
};

}  // namespace samp
