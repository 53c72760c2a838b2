#include "libsamp/eval/matching.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "libsamp/core/assignment.h"
#include "libsamp/data/tracking.h"

namespace samp::eval {
namespace {

double BoxIou(const Eigen::Vector4d& a, const Eigen::Vector4d& b) {
  const double iw = std::min(a[2], b[2]) - std::max(a[0], b[0]);
  const double ih = std::min(a[3], b[3]) - std::max(a[1], b[1]);
  if (iw <= 0 || ih <= 0) return 0.0;
  const double inter = iw * ih;
  const double area_a = (a[2] - a[0]) * (a[3] - a[1]), area_b = (b[2] - b[0]) * (b[3] - b[1]);
  return inter / std::max(1e-12, area_a + area_b - inter);
}

// Per frame and method: the IoU matches of the true boxes.
std::map<int, std::vector<std::vector<int>>> IouMatches(const EvalOptions& options, const SequenceInputs& inputs,
                                                       const std::vector<EvalMethod>& methods) {
  const PinholeCamera& camera = inputs.calibration.camera;
  std::map<int, std::vector<std::vector<int>>> iou_match;
  for (const auto& [frame, truths] : inputs.gt_by_frame) {
    std::vector<Eigen::Vector4d> truth_boxes;
    for (const ObjectLabel& t : truths) truth_boxes.push_back(ProjectedBox(t, camera));
    std::vector<std::vector<int>>& per_method = iou_match[frame];
    per_method.resize(methods.size());
    for (size_t m = 0; m < methods.size(); ++m) {
      if (methods[m].name == kStereo) continue;
      std::vector<Eigen::Vector4d> boxes;
      for (const ObjectLabel& e : LabelsAt(inputs, m, frame)) boxes.push_back(ProjectedBox(e, camera));
      per_method[m] = MatchBoxes(truth_boxes, boxes, options.min_iou);
    }
  }
  return iou_match;
}

// Per-track matching of method m: each true car gets the output track with
// which it shares the most IoU-matched frames (one-to-one, Hungarian on the
// overlap; every pair allowed at cost most + 1 - overlap, so the assignment
// maximises the total overlap).
std::map<int, int> TrackOfCar(const SequenceInputs& inputs, const SequenceMatches& matches, size_t m) {
  std::map<std::pair<int, int>, int> overlap;  // (true id, output track) -> frames
  std::set<int> car_ids, track_ids;
  for (const auto& [frame, truths] : inputs.gt_by_frame) {
    for (size_t t = 0; t < truths.size(); ++t) {
      const int e = matches.iou_match.at(frame)[m][t];
      if (e < 0) continue;
      const int track = LabelsAt(inputs, m, frame)[e].track_id;
      ++overlap[{truths[t].track_id, track}];
      car_ids.insert(truths[t].track_id);
      track_ids.insert(track);
    }
  }
  const std::vector<int> cars(car_ids.begin(), car_ids.end()), out_tracks(track_ids.begin(), track_ids.end());
  int most = 0;
  for (const auto& [pair, n] : overlap) most = std::max(most, n);
  std::vector<double> cost(cars.size() * out_tracks.size());
  for (size_t i = 0; i < cars.size(); ++i)
    for (size_t j = 0; j < out_tracks.size(); ++j) {
      const auto found = overlap.find({cars[i], out_tracks[j]});
      cost[i * out_tracks.size() + j] = most + 1 - (found == overlap.end() ? 0 : found->second);
    }
  const std::vector<int> assigned = SolveAssignment(cost, int(cars.size()), int(out_tracks.size()));
  std::map<int, int> track_of_car;
  for (size_t i = 0; i < cars.size(); ++i) {
    if (assigned[i] < 0 || !overlap.count({cars[i], out_tracks[assigned[i]]})) continue;
    track_of_car[cars[i]] = out_tracks[assigned[i]];
  }
  return track_of_car;
}

// Per-frame matching of method m by the distance of the origins (MatchTracks),
// with the CLEAR-MOT counts when `counts` is given. Truths that are not
// evaluated (SequenceInputs::evaluated) are ignored.
std::map<int, std::vector<int>> FrameMatch(const EvalOptions& options, const SequenceInputs& inputs, size_t m,
                                           TrackingCounts* counts) {
  std::vector<TrackedBox> truth_boxes, output_boxes;
  std::vector<std::pair<int, int>> output_index;  // (frame, index in the labels of the frame)
  for (const auto& [frame, truths] : inputs.gt_by_frame) {
    for (size_t t = 0; t < truths.size(); ++t) {
      TrackedBox box;
      box.frame = frame;
      box.track_id = truths[t].track_id;
      box.position = truths[t].position;
      box.ignore = !inputs.evaluated.at(frame)[t];
      truth_boxes.push_back(box);
    }
    const std::vector<ObjectLabel>& estimates = LabelsAt(inputs, m, frame);
    for (size_t e = 0; e < estimates.size(); ++e) {
      output_boxes.push_back(TrackedBox{frame, estimates[e].track_id, estimates[e].position, false});
      output_index.push_back({frame, int(e)});
    }
  }
  const std::vector<int> match = MatchTracks(truth_boxes, output_boxes, options.per_frame_distance, counts);
  std::map<int, std::vector<int>> frame_match;
  size_t i = 0;
  for (const auto& [frame, truths] : inputs.gt_by_frame) {
    std::vector<int>& per_truth = frame_match[frame];
    for (size_t t = 0; t < truths.size(); ++t, ++i) {
      per_truth.push_back(match[i] < 0 ? -1 : output_index[match[i]].second);
    }
  }
  return frame_match;
}

}  // namespace

Eigen::Isometry3d CameraFromObject(const ObjectLabel& label) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  const double c = std::cos(label.rotation_y), s = std::sin(label.rotation_y);
  t.linear() << c, 0, s, 0, 1, 0, -s, 0, c;
  t.translation() = label.position;
  return t;
}

Eigen::Vector4d ProjectedBox(const ObjectLabel& label, const PinholeCamera& camera) {
  const Eigen::Isometry3d camera_from_object = CameraFromObject(label);
  double x1 = 1e300, y1 = 1e300, x2 = -1e300, y2 = -1e300;
  bool any = false;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d corner((i & 1 ? 0.5 : -0.5) * label.length, (i & 2 ? -label.height : 0.0),
                                 (i & 4 ? 0.5 : -0.5) * label.width);
    const Eigen::Vector3d p = camera_from_object * corner;
    if (p.z() < 0.1) continue;
    const Eigen::Vector2d uv = camera.Project(p);
    x1 = std::min(x1, uv.x()), y1 = std::min(y1, uv.y());
    x2 = std::max(x2, uv.x()), y2 = std::max(y2, uv.y());
    any = true;
  }
  if (!any) return Eigen::Vector4d::Zero();
  x1 = std::clamp(x1, 0.0, camera.width - 1.0), x2 = std::clamp(x2, 0.0, camera.width - 1.0);
  y1 = std::clamp(y1, 0.0, camera.height - 1.0), y2 = std::clamp(y2, 0.0, camera.height - 1.0);
  return Eigen::Vector4d(x1, y1, x2, y2);
}

std::vector<int> MatchBoxes(const std::vector<Eigen::Vector4d>& truth, const std::vector<Eigen::Vector4d>& estimates,
                            double min_iou) {
  struct Pair {
    double iou;
    int t, e;
  };
  std::vector<Pair> pairs;
  for (size_t t = 0; t < truth.size(); ++t) {
    for (size_t e = 0; e < estimates.size(); ++e) {
      const double iou = BoxIou(truth[t], estimates[e]);
      if (iou >= min_iou) pairs.push_back({iou, int(t), int(e)});
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
    if (a.iou != b.iou) return a.iou > b.iou;
    if (a.t != b.t) return a.t < b.t;
    return a.e < b.e;
  });
  std::vector<int> match(truth.size(), -1);
  std::vector<bool> used(estimates.size(), false);
  for (const Pair& p : pairs) {
    if (match[p.t] >= 0 || used[p.e]) continue;
    match[p.t] = p.e;
    used[p.e] = true;
  }
  return match;
}

const std::vector<ObjectLabel>& LabelsAt(const SequenceInputs& inputs, size_t m, int frame) {
  static const std::vector<ObjectLabel> kNone;
  const auto found = inputs.labels[m].find(frame);
  return found == inputs.labels[m].end() ? kNone : found->second;
}

int SequenceMatches::Match(const SequenceInputs& inputs, int k, size_t m, int frame, size_t t) const {
  if (k == kPerFrame) return frame_match[m].at(frame)[t];
  const int index = iou_match.at(frame)[m][t];
  if (index < 0 || !tracked[m]) return index;
  const auto assigned = track_of_car[m].find(inputs.gt_by_frame.at(frame)[t].track_id);
  if (assigned == track_of_car[m].end() || LabelsAt(inputs, m, frame)[index].track_id != assigned->second) return -1;
  return index;
}

SequenceMatches MatchSequence(const EvalOptions& options, const SequenceInputs& inputs,
                              const std::vector<EvalMethod>& methods, std::vector<TrackingCounts>* tracking) {
  SequenceMatches matches;
  matches.iou_match = IouMatches(options, inputs, methods);
  matches.track_of_car.resize(methods.size());
  matches.frame_match.resize(methods.size());
  matches.tracked.assign(methods.size(), false);
  for (size_t m = 0; m < methods.size(); ++m) {
    if (methods[m].name == kStereo) continue;
    const bool tracked = methods[m].name != kDetections;
    matches.tracked[m] = tracked;
    if (tracked) matches.track_of_car[m] = TrackOfCar(inputs, matches, m);
    matches.frame_match[m] = FrameMatch(options, inputs, m, tracked ? &(*tracking)[m] : nullptr);
  }
  return matches;
}

}  // namespace samp::eval
