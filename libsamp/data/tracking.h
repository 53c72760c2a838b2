// Tracking-by-detection in 3D (see docs/sequence_format.md, "Tracking"):
// detections are placed in the world frame with the ego poses; every track
// runs a constant-velocity Kalman filter on its box centre with the
// detector's distance-dependent noise (3DOP-like: large along the viewing
// ray far away); detections are assigned to tracks by the Hungarian method on
// the squared Mahalanobis distance to the prediction within a chi-square gate;
// unmatched detections start new tracks; tracks end after max_misses
// consecutive frames without a detection. Deterministic.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "libsamp/data/track.h"

namespace samp {

struct TrackerOptions {
  // Detector noise: standard deviations (m) of a detected box centre in the
  // camera of its frame, d = the centre's horizontal distance (m): along the
  // horizontal viewing ray depth_sigma_a + depth_sigma_b d^2 (stereo depth
  // error grows with d^2), across it lateral_sigma_a + lateral_sigma_b d,
  // vertically height_sigma. Defaults: the 3DOP-like model of docs/synthetic.md.
  double depth_sigma_a = 0.1, depth_sigma_b = 0.001;
  double lateral_sigma_a = 0.05, lateral_sigma_b = 0.005;
  double height_sigma = 0.05;
  // Constant-velocity model: white acceleration noise (m/s^2) and, for a new
  // track, a zero velocity with standard deviation max_speed / 2 (m/s) per axis.
  double acceleration_sigma = 3.0;
  double max_speed = 20.0;
  // Gate: squared Mahalanobis distance of a detection to a track's predicted
  // centre (3 degrees of freedom); 16.27 keeps 99.9 % of true matches.
  double gate_chi2 = 16.27;
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
