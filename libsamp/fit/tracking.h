// Tracking-by-detection in 3D (see docs/sequence_format.md, "Tracking"):
// detections are placed in the world frame with the ego poses, tracks predict
// their position with a constant velocity, detections are assigned to tracks
// by the Hungarian method on the distance to the prediction within a gate,
// unmatched detections start new tracks, tracks end after max_misses
// consecutive frames without a detection. Deterministic.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "libsamp/fit/track.h"

namespace samp {

struct TrackerOptions {
  // Gate of an established track (velocity known): maximum distance, m, from
  // the predicted to the detected box centre in the world, per frame elapsed
  // the gate grows by gate_growth (uncertainty of the prediction).
  double gate_distance = 2.0;
  double gate_growth = 0.5;
  // A track with one detection has no velocity: its gate is
  // gate_distance + max_speed * dt (m/s, urban traffic).
  double max_speed = 20.0;
  // A track ends after this many consecutive frames without a detection.
  int max_misses = 2;
  // Tracks with fewer detections are dropped and reported in the summary.
  int min_track_length = 2;
  // Frames per second (dt between frames).
  double frame_rate_hz = 10.0;

  bool Check() const;
};

// The detections of one frame, in its camera, with the ego pose.
struct FrameDetections {
  int frame = 0;
  Eigen::Isometry3d world_from_camera = Eigen::Isometry3d::Identity();
  std::vector<ObjectLabel> detections;
};

// A linked track: one detection per frame it was seen in (increasing frames,
// gaps where it was missed), each with track_id = id and frame set.
struct LinkedTrack {
  int id = 0;
  std::vector<ObjectLabel> detections;
};

struct TrackingSummary {
  int num_detections = 0;
  int num_tracks = 0;           // kept (>= min_track_length)
  int num_short_tracks = 0;     // dropped
  int num_short_detections = 0; // detections in dropped tracks
  std::vector<std::string> short_tracks;  // "frames 3-3 (1 detection)" per dropped track
  std::string BriefReport() const;
};

// Links the detections of `frames` (in increasing frame order) into tracks.
// Track ids are 0, 1, ... in order of first appearance (then detection index).
std::vector<LinkedTrack> LinkDetections(const std::vector<FrameDetections>& frames,
                                        const TrackerOptions& options, TrackingSummary* summary);

// Groups labels that carry track ids (a KITTI tracking label file) into
// tracks, ordered by id; labels with track_id < 0 or of type DontCare are
// skipped. Throws samp::Error when a track has two labels in one frame.
// Tracks shorter than min_track_length are dropped and reported.
std::vector<LinkedTrack> TracksFromLabels(const std::vector<ObjectLabel>& labels,
                                          int min_track_length, TrackingSummary* summary);

// Minimum-cost assignment (Hungarian method, O(n^3)) on a rows x cols cost
// matrix (row-major); entries >= kNoAssignment are forbidden. Returns for each
// row the assigned column or -1.
constexpr double kNoAssignment = 1e18;
std::vector<int> SolveAssignment(const std::vector<double>& cost, int rows, int cols);

}  // namespace samp
