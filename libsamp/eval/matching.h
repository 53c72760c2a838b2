// The match stage of `samp eval` (internal to libsamp/eval; docs/evaluation.md
// "Matching"): which label of each method stands for each true car-frame, per
// track (one output track per true car for the whole sequence, frames matched
// by 2D IoU of the projected 3D boxes) and per frame (the nearest box of any
// track within per_frame_distance), and the CLEAR-MOT counts of the results.
#pragma once

#include <Eigen/Geometry>
#include <map>
#include <vector>

#include "libsamp/eval/eval_inputs.h"
#include "libsamp/eval/metrics.h"

namespace samp::eval {

// camera_from_object of a KITTI label (position, rotation_y).
Eigen::Isometry3d CameraFromObject(const ObjectLabel& label);

// The 2D box (x1, y1, x2, y2) of the label's projected 3D box, clipped to the
// image; all zero when nothing of it lies in front of the camera.
Eigen::Vector4d ProjectedBox(const ObjectLabel& label, const PinholeCamera& camera);

// Greedy one-to-one matching by decreasing IoU (at least min_iou). Returns per
// truth the index of the matched estimate or -1.
std::vector<int> MatchBoxes(const std::vector<Eigen::Vector4d>& truth, const std::vector<Eigen::Vector4d>& estimates,
                            double min_iou);

struct SequenceMatches {
  // Per frame, per method: per truth the index of its IoU-matched label or -1.
  std::map<int, std::vector<std::vector<int>>> iou_match;
  // Per method: whether it has track ids (the results; not the detections,
  // which keep the IoU match per frame under the per-track matching), and
  // true car id -> its output track (per-track matching).
  std::vector<bool> tracked;
  std::vector<std::map<int, int>> track_of_car;
  // Per method: frame -> per truth the index of its per-frame match or -1.
  std::vector<std::map<int, std::vector<int>>> frame_match;

  // The index of the label of method m matching truth t of `frame` under
  // matching k (kPerTrack, kPerFrame), -1 when none; labels as in `inputs`.
  int Match(const SequenceInputs& inputs, int k, size_t m, int frame, size_t t) const;
};

// Both matchings of every method but the stereo baseline; adds the CLEAR-MOT
// counts of each tracked result (not the detections) to (*tracking)[m].
SequenceMatches MatchSequence(const EvalOptions& options, const SequenceInputs& inputs,
                              const std::vector<EvalMethod>& methods, std::vector<TrackingCounts>* tracking);

// The labels of method m at `frame` (empty when none).
const std::vector<ObjectLabel>& LabelsAt(const SequenceInputs& inputs, size_t m, int frame);

}  // namespace samp::eval
