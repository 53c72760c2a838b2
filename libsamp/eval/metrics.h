// The paper's evaluation measures (docs/evaluation.md): accuracy, completeness
// and F1 of an estimated point set against a true one at a distance threshold
// tau, and the pose errors (translation, absolute yaw). Exact nearest
// neighbours (core/nearest_neighbor.h). Free functions and an
// immutable index: thread-safe.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "libsamp/core/nearest_neighbor.h"
#include "libsamp/core/util.h"

namespace samp {

// For each query point, the distance to its nearest reference point, or +inf
// beyond max_distance.
std::vector<double> NearestDistances(const std::vector<Eigen::Vector3d>& queries,
                                     const std::vector<Eigen::Vector3d>& reference,
                                     double max_distance);

struct ShapeScores {
  double accuracy = 0.0;      // share of estimated points with a true point within tau
  double completeness = 0.0;  // share of true points with an estimated point within tau
  double f1 = 0.0;            // harmonic mean (0 when both are 0)
};

// Both directions of nearest-neighbour distances between an estimated and a
// true point set, enough to score any tau <= max_tau.
struct ShapeComparison {
  std::vector<double> estimated_to_truth;  // per estimated point
  std::vector<double> truth_to_estimated;  // per true point
  double max_tau = 0.0;

  // Scores at tau (<= max_tau). An empty estimated set has accuracy 0; an
  // empty true set completeness 0.
  ShapeScores At(double tau) const;
};

ShapeComparison CompareShapes(const std::vector<Eigen::Vector3d>& estimated,
                              const std::vector<Eigen::Vector3d>& truth, double max_tau);

// Absolute yaw difference in degrees, in [0, 180] (wrapped; a 180-degree flip counts as 180).
double YawErrorDeg(double estimated_yaw, double true_yaw);

// Mean of a list (0 for an empty list); the median is core/util.h Median.
double Mean(const std::vector<double>& values);


// ---------------------------------------------------------------------------
// Tracking (CLEAR-MOT, Bernardin & Stiefelhagen 2008): a box of a tracking
// result or of the ground truth in one frame, by its object origin (the bottom
// centre) in the camera of that frame.
struct TrackedBox {
  int frame = 0;
  int track_id = -1;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  // Ground truth only: a box that is neither counted when missed nor makes the
  // output box matched to it a false positive (e.g. too few visible pixels).
  bool ignore = false;
};

// CLEAR-MOT counts of one or more sequences (sum them with Add).
struct TrackingCounts {
  int true_cars = 0;        // ground-truth tracks with a counted box
  int true_boxes = 0;       // counted ground-truth boxes (car-frames)
  int output_tracks = 0;
  int output_boxes = 0;     // not matched to an ignored true box
  int matches = 0;          // counted true boxes with an output box
  int misses = 0;           // FN: counted true boxes without
  int false_positives = 0;  // FP: output boxes matched to no true box
  int id_switches = 0;      // IDSW: a true car's output track differs from its previous one
  int fragmentations = 0;   // FRAG: a true car's match resumed after unmatched frames
  int tracks_on_cars = 0;   // sum over matched true cars of the distinct output tracks matched to them
  int in_main_track = 0;    // matches in their car's main track (the output track with most of them)
  int missed_cars = 0;      // true cars never matched
  int false_tracks = 0;     // output tracks never matched to a counted true box
  double distance_sum = 0;  // over matches, m (MOTP)

  void Add(const TrackingCounts& other);
  // 1 - (FN + FP + IDSW) / true boxes.
  double Mota() const;
  // Mean distance of the matches, m.
  double Motp() const;
  // Distinct output tracks per matched true car (1 = no fragments, no switches).
  double TracksPerCar() const;
  // Share of the matches that lie in their car's main track.
  double MainTrackShare() const;
};

// Per-frame matching of one sequence: frame by frame (increasing), a true car
// keeps the output track it matched in its previous matched frame while that
// track's box is within max_distance; the other boxes are matched one-to-one
// by the Hungarian method on the distance, within max_distance. Returns for
// each true box (in the order given) the index of its output box, or -1.
// `counts` (optional) receives this sequence's CLEAR-MOT counts (added to it).
// Track ids: the truth's are unique per car, the output's per track (output
// boxes with track_id < 0 count each as a track of their own).
std::vector<int> MatchTracks(const std::vector<TrackedBox>& truth, const std::vector<TrackedBox>& output,
                             double max_distance, TrackingCounts* counts);

}  // namespace samp
