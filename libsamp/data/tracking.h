// Tracking by detection in 3D (docs/sequence_format.md, "Tracking by
// detection"). Two stages, deterministic:
//  1. Online: detections are placed in the world with the ego poses and
//     compared in the ground plane; every track runs a constant-velocity
//     Kalman filter on its box's bottom centre (2-D, ground plane) with the
//     detector's distance-dependent noise (a stereo detector: large along the
//     viewing ray, growing with distance) and keeps its mean box size, height
//     and axis (yaw modulo 180 degrees: a flipped box is the same car). Per
//     frame all live tracks and detections are assigned at once (Hungarian
//     method) on the sum of the squared Mahalanobis distances of position,
//     size, height and axis, each within its gate. A new track is tentative
//     until it has confirm_hits detections; tentative tracks end after
//     tentative_max_misses missed frames, confirmed ones after max_misses.
//  2. Offline: fragments are joined when their constant-velocity fits agree
//     across the gap (each extrapolated to the gap's middle), and the tails
//     of two tracks are swapped where that makes both continue smoothly (an
//     identity switch where two cars' tracks cross).
// Tracks with fewer than min_track_length detections are dropped at the end.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "libsamp/data/track.h"

namespace samp {

class OptionsJson;

struct TrackerOptions {
  // Detector noise: standard deviations (m) of a detected box's bottom centre
  // in the camera of its frame, d = its horizontal distance (m). Along the
  // horizontal viewing ray along_sigma_a + along_sigma_b d + along_sigma_c d^2,
  // across it across_sigma_a + across_sigma_b d, vertically vertical_sigma_a +
  // vertical_sigma_b d. Defaults: a stereo 3D detector (median position error
  // ~0.35 m below 20 m, ~0.6 m beyond 40 m, vertical 0.2-0.3 m; the
  // synthetic detector model, docs/synthetic.md).
  double along_sigma_a = 0.25, along_sigma_b = 0.015, along_sigma_c = 0.0;
  double across_sigma_a = 0.1, across_sigma_b = 0.005;
  double vertical_sigma_a = 0.2, vertical_sigma_b = 0.002;
  // Std. dev. of each detected box dimension h, w, l (m) and of the detected
  // yaw modulo 180 degrees (deg).
  double size_sigma = 0.3;
  double yaw_sigma_deg = 10.0;
  // Constant-velocity model: white acceleration noise (m/s^2); a new track
  // starts with zero velocity of std. dev. max_speed / 2 (m/s) per axis.
  double acceleration_sigma = 3.0;
  double max_speed = 20.0;
  // Gates, each on a squared Mahalanobis distance: ground-plane position
  // (2 dof, 13.82 = 99.9 %), box size (3 dof, 16.27 = 99.9 %), height of the
  // bottom centre (1 dof, 10.83 = 99.9 %); and the axis difference (deg).
  double gate_chi2 = 13.82;
  double size_gate_chi2 = 16.27;
  double height_gate_chi2 = 10.83;
  double yaw_gate_deg = 45.0;
  // A tentative track's costs carry this penalty, so that a confirmed track
  // wins a contested detection.
  double tentative_penalty = 4.0;
  // Birth: a track is confirmed with this many detections; until then it ends
  // after more than tentative_max_misses consecutive missed frames.
  int confirm_hits = 2;
  int tentative_max_misses = 1;
  // Death: a confirmed track ends after more than max_misses consecutive
  // frames without a detection.
  int max_misses = 3;
  // Second stage: join a fragment's end to another's start at most
  // max_join_gap missed frames later when the link cost (squared Mahalanobis
  // distance of the constant-velocity fits' positions and velocities at the
  // gap's middle, plus size, height and axis terms) is at most join_gate_chi2.
  bool join_fragments = true;
  int max_join_gap = 10;
  double join_gate_chi2 = 27.88;
  // Second stage: swap two tracks' tails when the two links after the swap
  // cost less than before by at least swap_margin (squared Mahalanobis units).
  bool resolve_switches = true;
  double swap_margin = 6.0;
  // Detections per side in the constant-velocity fits of the second stage.
  int fit_window = 5;
  // Tracks with fewer detections are dropped and reported in the summary.
  int min_track_length = 2;
  // Frames per second (dt between frames).
  double frame_rate_hz = 10.0;
  // The summary warns when a sequence's median track is shorter (frames).
  int warn_median_length = 5;
  // Robust cues: a single cue (box size, height or axis) outside its gate
  // costs its gate's value instead of forbidding the pair, so a wrong box
  // length or a misturned box does not start a new track when position and
  // motion agree (two cues outside their gates still forbid it); the outlying
  // cue does not update the track's mean. The same holds for fragment joins.
  // Off: every cue gates (the behaviour before; docs/detector_calibration.md).
  bool robust_cues = false;

  void Check() const;  // throws samp::Error naming the field
  // Every field as a JSON object (for config.json; OptionFields below).
  std::string ToJson() const;
};

// Every TrackerOptions field, for config.json's writer and reader, through
// the option table (data/tracker_option_table.h; pipeline/fit_config.h owns
// config.json).
void OptionFields(OptionsJson& io, TrackerOptions& o);

// Covariance (m^2) of a detected box's bottom centre `position` in the camera
// of its frame under the detector noise model of `options` (along the
// horizontal viewing ray, across it, vertically; TrackerOptions). The tracker
// gates with it; the fitter weighs the detections as pose observations with
// it (TrackFrame::detection_covariance, fit/costs/detection_position.h).
Eigen::Matrix3d DetectionCovariance(const Eigen::Vector3d& position, const TrackerOptions& options);

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
  // Second stage (LinkDetections only).
  int num_online_tracks = 0;    // tracks of the online stage, before joins and drops
  int num_joins = 0;            // fragment ends joined to a later fragment
  int num_swaps = 0;            // tails swapped between two tracks
  // Detections identical to an earlier one of the same frame (bottom centre
  // within 1 cm, box dimensions within 1 cm, axis within 0.5 degrees):
  // dropped before linking and reported ("frame 4: 999 duplicates").
  int num_duplicates = 0;
  std::vector<std::string> duplicates;
  double median_track_length = 0.0;  // detections per kept track
  // "median track length 2.0 frames < 5: ..." when the median is short.
  std::vector<std::string> warnings;
  std::string BriefReport() const;
  std::string ToJson() const;
};

// Links the detections of `frames` (in increasing frame order) into tracks.
// Track ids are 0, 1, ... in order of first appearance (then detection index).
// The online assignment is linear in the detections per frame: pairs beyond
// the position gate are never formed (a spatial hash), and the assignment is
// solved per connected group of gated pairs (the same optimum as one
// assignment over all). Duplicate detections are dropped and counted.
std::vector<LinkedTrack> LinkDetections(const std::vector<FrameDetections>& frames,
                                        const TrackerOptions& options, TrackingSummary* summary);

// Groups labels that carry track ids (a KITTI tracking label file) into
// tracks, ordered by id; labels with track_id < 0 or of type DontCare are
// skipped. Throws samp::Error when a track has two labels in one frame.
// Tracks shorter than min_track_length are dropped and reported.
std::vector<LinkedTrack> TracksFromLabels(const std::vector<ObjectLabel>& labels,
                                          int min_track_length, TrackingSummary* summary);

}  // namespace samp
