#include "libsamp/eval/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <set>

#include "libsamp/core/error.h"
#include "libsamp/core/pose.h"
#include "libsamp/core/assignment.h"
#include "libsamp/data/tracking.h"

namespace samp {

std::vector<double> NearestDistances(const std::vector<Eigen::Vector3d>& queries,
                                     const std::vector<Eigen::Vector3d>& reference,
                                     double max_distance) {
  const RadiusNearestNeighbor index(reference, max_distance);
  std::vector<double> distances(queries.size());
  for (size_t i = 0; i < queries.size(); ++i) distances[i] = index.Distance(queries[i]);
  return distances;
}

ShapeScores ShapeComparison::At(double tau) const {
  SAMP_CHECK(tau >= 0 && tau <= max_tau * (1.0 + 1e-12))
      << "ShapeComparison::At: tau " << tau << " outside [0, " << max_tau << "]";
  auto share = [tau](const std::vector<double>& d) {
    if (d.empty()) return 0.0;
    const auto n = std::count_if(d.begin(), d.end(), [tau](double x) { return x <= tau; });
    return double(n) / double(d.size());
  };
  ShapeScores s;
  s.accuracy = share(estimated_to_truth);
  s.completeness = share(truth_to_estimated);
  s.f1 = s.accuracy + s.completeness > 0
             ? 2.0 * s.accuracy * s.completeness / (s.accuracy + s.completeness)
             : 0.0;
  return s;
}

ShapeComparison CompareShapes(const std::vector<Eigen::Vector3d>& estimated,
                              const std::vector<Eigen::Vector3d>& truth, double max_tau) {
  ShapeComparison c;
  c.max_tau = max_tau;
  c.estimated_to_truth = NearestDistances(estimated, truth, max_tau);
  c.truth_to_estimated = NearestDistances(truth, estimated, max_tau);
  return c;
}

double YawErrorDeg(double estimated_yaw, double true_yaw) {
  double d = std::fmod(std::abs(estimated_yaw - true_yaw), 2.0 * kPi);
  if (d > kPi) d = 2.0 * kPi - d;
  return d * 180.0 / kPi;
}

double Mean(const std::vector<double>& values) {
  if (values.empty()) return 0.0;
  return std::accumulate(values.begin(), values.end(), 0.0) / double(values.size());
}



void TrackingCounts::Add(const TrackingCounts& o) {
  true_cars += o.true_cars;
  true_boxes += o.true_boxes;
  output_tracks += o.output_tracks;
  output_boxes += o.output_boxes;
  matches += o.matches;
  misses += o.misses;
  false_positives += o.false_positives;
  id_switches += o.id_switches;
  fragmentations += o.fragmentations;
  tracks_on_cars += o.tracks_on_cars;
  in_main_track += o.in_main_track;
  missed_cars += o.missed_cars;
  false_tracks += o.false_tracks;
  distance_sum += o.distance_sum;
}

double TrackingCounts::Mota() const {
  if (true_boxes == 0) return 0.0;
  return 1.0 - double(misses + false_positives + id_switches) / true_boxes;
}

double TrackingCounts::Motp() const { return matches > 0 ? distance_sum / matches : 0.0; }

double TrackingCounts::TracksPerCar() const {
  const int matched_cars = true_cars - missed_cars;
  return matched_cars > 0 ? double(tracks_on_cars) / matched_cars : 0.0;
}

double TrackingCounts::MainTrackShare() const { return matches > 0 ? double(in_main_track) / matches : 0.0; }

namespace {

// The output track of output box o; a box without a track id is a track of its own.
int TrackKey(const std::vector<TrackedBox>& output, int o) {
  return output[o].track_id >= 0 ? output[o].track_id : -1 - o;
}

// Matches the true boxes `t_boxes` of one frame to its output boxes `o_boxes`:
// first the correspondences of each car's previous matched frame that still
// hold, then the rest by Hungarian on the distance. Updates *last_track (true
// car -> output track of its last matched frame).
void MatchFrame(const std::vector<TrackedBox>& truth, const std::vector<TrackedBox>& output,
                const std::vector<int>& t_boxes, const std::vector<int>& o_boxes, double max_distance,
                std::vector<int>* match, std::vector<int>* truth_of_output, std::map<int, int>* last_track) {
  auto distance = [&](int t, int o) { return (truth[t].position - output[o].position).norm(); };
  for (int t : t_boxes) {
    const auto last = last_track->find(truth[t].track_id);
    if (last == last_track->end()) continue;
    for (int o : o_boxes) {
      if ((*truth_of_output)[o] >= 0 || TrackKey(output, o) != last->second || distance(t, o) > max_distance) continue;
      (*match)[t] = o, (*truth_of_output)[o] = t;
      break;
    }
  }
  std::vector<int> rows, cols;
  for (int t : t_boxes)
    if ((*match)[t] < 0) rows.push_back(t);
  for (int o : o_boxes)
    if ((*truth_of_output)[o] < 0) cols.push_back(o);
  std::vector<double> cost(rows.size() * cols.size(), kNoAssignment);
  for (size_t r = 0; r < rows.size(); ++r)
    for (size_t c = 0; c < cols.size(); ++c) {
      const double d = distance(rows[r], cols[c]);
      if (d <= max_distance) cost[r * cols.size() + c] = d;
    }
  const std::vector<int> assigned = SolveAssignment(cost, int(rows.size()), int(cols.size()));
  for (size_t r = 0; r < rows.size(); ++r) {
    if (assigned[r] < 0) continue;
    (*match)[rows[r]] = cols[assigned[r]];
    (*truth_of_output)[cols[assigned[r]]] = rows[r];
  }
  for (int t : t_boxes)
    if ((*match)[t] >= 0) (*last_track)[truth[t].track_id] = TrackKey(output, (*match)[t]);
}

// The counts of one true car over its boxes in frame order (ignored boxes skipped).
void CountCar(const std::vector<TrackedBox>& truth, const std::vector<TrackedBox>& output,
              const std::vector<int>& match, const std::vector<int>& boxes, TrackingCounts* c) {
  std::map<int, int> per_track;
  bool counted = false, was_matched = false, gap = false;
  int previous = 0;
  bool has_previous = false;
  for (int t : boxes) {
    if (truth[t].ignore) continue;
    counted = true;
    ++c->true_boxes;
    if (match[t] < 0) {
      ++c->misses;
      if (was_matched) gap = true;
      continue;
    }
    ++c->matches;
    c->distance_sum += (truth[t].position - output[match[t]].position).norm();
    const int key = TrackKey(output, match[t]);
    ++per_track[key];
    if (has_previous && key != previous) ++c->id_switches;
    if (gap) ++c->fragmentations;
    previous = key, has_previous = true, was_matched = true, gap = false;
  }
  if (!counted) return;
  ++c->true_cars;
  if (per_track.empty()) {
    ++c->missed_cars;
    return;
  }
  c->tracks_on_cars += int(per_track.size());
  int main = 0;
  for (const auto& [key, n] : per_track) main = std::max(main, n);
  c->in_main_track += main;
}

// The CLEAR-MOT counts of a matching.
TrackingCounts CountTracking(const std::vector<TrackedBox>& truth, const std::vector<TrackedBox>& output,
                             const std::map<int, std::vector<int>>& truth_of_frame, const std::vector<int>& match,
                             const std::vector<int>& truth_of_output) {
  TrackingCounts c;
  std::map<int, std::vector<int>> boxes_of_car;  // per true car, its boxes in frame order
  for (const auto& [frame, t_boxes] : truth_of_frame)
    for (int t : t_boxes) boxes_of_car[truth[t].track_id].push_back(t);
  std::set<int> matched_tracks;  // output tracks matched to any true box
  for (size_t o = 0; o < output.size(); ++o)
    if (truth_of_output[o] >= 0) matched_tracks.insert(TrackKey(output, int(o)));
  for (const auto& [car, boxes] : boxes_of_car) CountCar(truth, output, match, boxes, &c);
  std::set<int> tracks;
  for (size_t o = 0; o < output.size(); ++o) {
    tracks.insert(TrackKey(output, int(o)));
    const int t = truth_of_output[o];
    if (t >= 0 && truth[t].ignore) continue;
    ++c.output_boxes;
    if (t < 0) ++c.false_positives;
  }
  c.output_tracks = int(tracks.size());
  for (int key : tracks) c.false_tracks += matched_tracks.count(key) == 0;
  return c;
}

}  // namespace

std::vector<int> MatchTracks(const std::vector<TrackedBox>& truth, const std::vector<TrackedBox>& output,
                             double max_distance, TrackingCounts* counts) {
  SAMP_CHECK(max_distance > 0) << "MatchTracks: max_distance must be > 0";
  std::map<int, std::vector<int>> truth_of_frame, output_of_frame;
  for (size_t i = 0; i < truth.size(); ++i) truth_of_frame[truth[i].frame].push_back(int(i));
  for (size_t i = 0; i < output.size(); ++i) output_of_frame[output[i].frame].push_back(int(i));
  std::vector<int> match(truth.size(), -1);
  std::vector<int> truth_of_output(output.size(), -1);
  std::map<int, int> last_track;
  for (const auto& [frame, t_boxes] : truth_of_frame) {
    const auto found = output_of_frame.find(frame);
    if (found == output_of_frame.end()) continue;
    MatchFrame(truth, output, t_boxes, found->second, max_distance, &match, &truth_of_output, &last_track);
  }
  if (counts != nullptr) counts->Add(CountTracking(truth, output, truth_of_frame, match, truth_of_output));
  return match;
}

}  // namespace samp
