// Synthetic KITTI-like stereo sequences with ground truth (docs/synthetic.md).
// CAD cars on a street (the default preset: lanes, kerbs, facades, clutter,
// parked rows, traffic, ego sway, sun and shadows) or on the clean preset's
// textured road between building blocks, rendered with Embree into a
// KITTI-calibrated stereo rig on a moving ego car; the disparity either from
// OpenCV StereoSGBM on the rendered pair or the true disparity plus a noise
// model; detections from a stereo detector's error model (detector_model.h).
//
// The output is exactly the sequence layout `samp fit` reads:
//   SEQ/calib/<seq>.txt, image_2/, image_3/, disparity/, detections/, planes/, poses/<seq>.txt
// plus the ground truth in SEQ/gt/ (label_02/<seq>.txt, depth/, obj_map/, meshes/, cars.json,
// detector_model.json: the detector's true noise model, TrueDetectorNoiseModel).
// Everything is a function of the options (seed included): same options, same bytes.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "libsamp/data/sequence_layout.h"
#include "libsamp/synth/synth_options.h"

namespace samp {

// Where the cars come from: CAD files canonicalised with a manifest (as the
// trainer does), and/or meshes that are already canonical (PLY, OBJ, ...).
struct SynthCarSource {
  // Folder searched recursively for CAD files ("" = none).
  std::string cad_folder;
  // Optional training manifest (JSON) for canonicalisation and skips ("" = none).
  std::string manifest_path;
  // Use only these shape names (manifest name or file stem); empty = all not skipped.
  std::vector<std::string> only;
  // Ignore the manifest's `skip` flags for the cars named in `only` (held-out cars
  // are usually marked skip in the training manifest).
  bool ignore_skip_for_only = true;
  // Meshes already in the canonical frame.
  std::vector<std::string> canonical_meshes;

  void Check() const;
};

// Loads, canonicalises and validates the cars, sorted by name. Throws samp::Error
// naming the file when a car cannot be used or when no car is left.
std::vector<SynthCar> LoadSynthCars(const SynthCarSource& source);

struct SynthSummary {
  std::vector<SynthSequenceInfo> sequences;
  int num_tracks = 0;
  int num_standing = 0, num_straight = 0, num_turning = 0;
  int num_parked = 0;  // among the standing
  double car_disparity_mae_px = 0.0, car_disparity_valid_fraction = 0.0;  // over all sequences
  double seconds = 0.0;
  std::string BriefReport() const;
};

// The ground-truth trajectory of a car (or of the ego car): the poses (x, y, z,
// yaw) of frames 0..num_frames-1 at times (t - origin_frame) / frame_rate_hz
// from origin_pose with constant speed and yaw rate, moved by the fitter's
// motion model (fit/motion_model.h PredictMotion), yaw wrapped to (-pi, pi].
// SynthesizeSequences places every car and the ego camera this way.
std::vector<Eigen::Vector4d> SynthTrajectory(const Eigen::Vector4d& origin_pose, double speed, double yaw_rate,
                                             int num_frames, int origin_frame, double frame_rate_hz);

// SEQ/gt/detector_model.json: the synthetic detector's true noise model
// (TrueDetectorNoiseModel over the cars' distance range), in the format of
// data/detector_noise.h, for `samp fit --detector-model`.
std::string SynthDetectorModelPath(const SequenceLayout& layout);

// Writes options.num_sequences sequences from `cars` (at least one). Every file
// is written atomically; config.json with the effective options goes to the root.
SynthSummary SynthesizeSequences(const SynthOptions& options, const std::vector<SynthCar>& cars);

}  // namespace samp
