// Synthetic KITTI-like stereo sequences with ground truth (docs/synthetic.md).
// A textured road plane, textured building blocks beside the road and CAD cars
// with plain paint, rendered with Embree into a KITTI-calibrated stereo rig on
// a moving ego car; the disparity either from OpenCV StereoSGBM on the rendered
// pair or the true disparity plus a noise model; detections are the true boxes
// with distance-dependent noise, 180-degree flips and misses.
//
// The output is exactly the sequence layout `samp fit` reads (issue 3):
//   SEQ/calib/<seq>.txt, image_2/, image_3/, disparity/, detections/, planes/, poses/<seq>.txt
// plus the ground truth in SEQ/gt/ (label_02/<seq>.txt, depth/, obj_map/, meshes/, cars.json).
// Everything is a function of the options (seed included): same options, same bytes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "libsamp/core/mesh.h"

namespace samp {

// A car mesh in the canonical object frame (origin bottom centre, x front, y down, z left).
struct SynthCar {
  std::string name;
  Mesh mesh;
};

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

enum class DisparitySource {
  kStereoSgbm,     // OpenCV StereoSGBM on the rendered, noisy image pair
  kTrueWithNoise,  // true disparity + the noise model below (fast, for tests)
};

struct SynthOptions {
  // Root folder; sequence i is written to <output_folder>/<seq>, seq = %06d of first_sequence + i.
  std::string output_folder;
  // Seed of every random choice (scenes, motion, noise). Logged and stored in config.json.
  uint64_t seed = 1;
  int num_sequences = 1;
  int first_sequence = 0;
  // Cars per sequence (each a different CAD car when enough are given).
  int cars_per_sequence = 3;
  // Frames per sequence and frame rate (KITTI stereo 2015 multiview: 21 frames, 10 Hz).
  int num_frames = 21;
  double frame_rate_hz = 10.0;

  // Camera: KITTI's rectified left camera (P2) and the stereo baseline.
  int width = 1242, height = 375;
  double focal_px = 721.5377;
  double cx_px = 609.5593, cy_px = 172.854;
  double baseline = 0.5327;
  // Height of the camera above the road, metres.
  double camera_height = 1.65;

  // Distance of each car to the camera at the middle frame, metres (stratified near/far).
  double min_distance = 5.0, max_distance = 45.0;
  // Motion mix: car i of the whole set is standing / straight / turning by i mod 3.
  // Straight speeds, m/s (urban: 11-47 km/h).
  double min_speed = 3.0, max_speed = 13.0;
  // Turning: speeds and absolute yaw rates (rad/s).
  double min_turn_speed = 2.5, max_turn_speed = 8.0;
  double min_yaw_rate = 0.15, max_yaw_rate = 0.5;
  // Ego car: forward speed range (m/s) and maximal absolute yaw rate (rad/s).
  double min_ego_speed = 0.0, max_ego_speed = 8.0;
  double max_ego_yaw_rate = 0.04;

  // Image noise: Gaussian, std. dev. in 8-bit grey levels, independent per pixel and camera.
  double image_noise_sigma = 2.0;

  DisparitySource disparity = DisparitySource::kStereoSgbm;
  // kTrueWithNoise: Gaussian disparity noise (px) on the background and on cars
  // (untextured paint), a share of invalid pixels (0) and of uniform outliers.
  double disparity_sigma_px = 0.3;
  double car_disparity_sigma_px = 0.8;
  double invalid_fraction = 0.1;
  double outlier_fraction = 0.02;

  // Detections (3DOP-like): std. dev. of the position along the viewing ray
  // a + b d^2 and across it (horizontal) c + e d, d the distance in metres.
  double det_depth_sigma_a = 0.1, det_depth_sigma_b = 0.001;
  double det_lateral_sigma_a = 0.05, det_lateral_sigma_b = 0.005;
  double det_height_sigma = 0.05;
  // Yaw noise std. dev. (deg) f + g d, probability of a 180-degree flip, of a miss.
  double det_yaw_sigma_deg_a = 3.0, det_yaw_sigma_deg_b = 0.15;
  double det_flip_probability = 0.08;
  double det_miss_probability = 0.05;
  // Relative std. dev. of the box size h, w, l; std. dev. of the 2D box corners (px).
  double det_size_sigma = 0.05;
  double det_box_sigma_px = 2.0;
  // Cars with fewer visible pixels than this are never detected.
  int det_min_pixels = 150;

  // Print progress.
  bool show_progress = true;

  void Check() const;
  std::string ToJson() const;
};

struct SynthSequenceInfo {
  std::string name;        // 6 digits
  std::string folder;
  int num_cars = 0;
  int num_detections = 0;  // over all frames
  int num_gt_labels = 0;   // car-frames with at least one visible pixel
};

struct SynthSummary {
  std::vector<SynthSequenceInfo> sequences;
  int num_tracks = 0;
  int num_standing = 0, num_straight = 0, num_turning = 0;
  double seconds = 0.0;
  std::string BriefReport() const;
};

// Writes options.num_sequences sequences from `cars` (at least one). Every file
// is written atomically; config.json with the effective options goes to the root.
SynthSummary SynthesizeSequences(const SynthOptions& options, const std::vector<SynthCar>& cars);

}  // namespace samp
