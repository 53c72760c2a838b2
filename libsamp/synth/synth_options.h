// What the synthetic-sequence generator's stages (scene.h, sequence_writer.h)
// share with its interface (synth.h): the cars, the options and the record of
// one written sequence. Kept apart from synth.h so that the stages include
// downwards only.
#pragma once

#include <cstdint>
#include <string>

#include "libsamp/core/mesh.h"
#include "libsamp/synth/detector_model.h"
#include "libsamp/synth/street_scene.h"

namespace samp {

// A car mesh in the canonical object frame (origin bottom centre, x front, y down, z left).
struct SynthCar {
  std::string name;
  Mesh mesh;
  // Triangles [0, num_body_triangles) are the body, the rest wheels (shaded as
  // tyres); -1 = all body.
  int num_body_triangles = -1;
};

enum class DisparitySource {
  kStereoSgbm,     // OpenCV StereoSGBM on the rendered, noisy image pair
  kTrueWithNoise,  // true disparity + the noise model below (fast, for tests)
};

// Which scenes to make: the realistic street (the default, docs/synthetic.md
// "Street") or the clean scenes (`--preset clean`, docs/synthetic.md "Presets").
enum class SynthScene { kStreet, kClean };

// The folders a sequence is written in: samp's (the default; docs/sequence_format.md)
// or KITTI tracking's own (`--layout kitti-tracking`: OUT/training/image_02|image_03/<seq>/,
// calib/, oxts/, label_02/, and the detections in OUT/detections/<seq>.txt;
// data/kitti_tracking.h). Sequence names: %06d in samp's, %04d in KITTI's.
enum class SynthLayout { kSamp, kKittiTracking };

struct SynthOptions {
  // Root folder; sequence i is written to <output_folder>/<seq>, seq = %06d of first_sequence + i.
  std::string output_folder;
  // Seed of every random choice (scenes, motion, noise). Logged and stored in config.json.
  uint64_t seed = 1;
  int num_sequences = 1;
  int first_sequence = 0;
  // Scene kind; SynthOptions::Clean() gives every default of the clean preset.
  SynthScene scene = SynthScene::kStreet;
  // Street layout (kStreet only).
  StreetOptions street;
  // Traffic cars per sequence (each a different CAD car when enough are given).
  int cars_per_sequence = 3;
  // Parked cars per sequence in the parking lanes' rows (kStreet only; standing).
  int parked_cars_per_sequence = 3;
  // Shares of the traffic cars that stand (waiting) and that turn; the rest drive
  // straight (kStreet; kClean: car i is standing / straight / turning by i mod 3).
  double standing_share = 0.2, turning_share = 0.25;
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
  // Street: the share of a sequence's cars (parked and traffic) nearer than 20 m
  // at the middle frame. Each parked row and each traffic car is drawn near
  // (min_distance-20 m) while the sequence's realised near share, counted with
  // it, would stay below it, else far (20 m-max_distance).
  double near_share = 0.65;
  // Straight speeds, m/s (urban: 11-47 km/h).
  double min_speed = 3.0, max_speed = 13.0;
  // Turning: speeds and absolute yaw rates (rad/s).
  double min_turn_speed = 2.5, max_turn_speed = 8.0;
  double min_yaw_rate = 0.15, max_yaw_rate = 0.5;
  // Ego car: forward speed range (m/s) and maximal absolute yaw rate (rad/s).
  double min_ego_speed = 0.0, max_ego_speed = 15.0;
  double max_ego_yaw_rate = 0.02;
  // Ego sway (kStreet): pitch and roll amplitudes (deg) and vertical bounce (m) at
  // max_ego_speed (scaled by speed / max_ego_speed, at least 30 %), and the
  // maximal constant pitch of the camera mounting (deg).
  double ego_pitch_sway_deg = 0.6, ego_roll_sway_deg = 0.3, ego_bounce = 0.015;
  double ego_max_pitch_offset_deg = 0.8;

  // Lighting and paint (kStreet): sun elevation range (deg), paint clear coat
  // (Blinn-Phong sun highlight strength and exponent, Schlick F0 of the sky
  // reflection), glass F0, relative strength of the paint's texture (dirt,
  // orange peel), and cast shadows. Calibrated so that raw SGBM stereo scores as
  // libELAS on KITTI (docs/synthetic.md "Calibration", docs/results.md).
  double min_sun_elevation_deg = 20.0, max_sun_elevation_deg = 65.0;
  double paint_specular = 0.6, paint_shininess = 80.0, paint_fresnel_f0 = 0.04;
  double glass_fresnel_f0 = 0.04;
  double paint_texture = 0.3;
  // Mean albedo of what is seen through the tinted windows (the interior), drawn
  // as a blotchy texture on the glass; 0 = black glass.
  double window_interior_albedo = 0.0;
  bool shadows = true;

  // Image noise: Gaussian, std. dev. in 8-bit grey levels, independent per pixel and camera
  // (the clean preset: 2).
  double image_noise_sigma = 0.7;

  SynthLayout layout = SynthLayout::kSamp;

  DisparitySource disparity = DisparitySource::kStereoSgbm;
  // kTrueWithNoise: Gaussian disparity noise (px) on the background and on cars
  // (untextured paint), a share of invalid pixels (0) and of uniform outliers.
  double disparity_sigma_px = 0.3;
  double car_disparity_sigma_px = 0.8;
  double invalid_fraction = 0.1;
  double outlier_fraction = 0.02;

  // The detector's errors (detector_model.h; defaults: a stereo 3D detector).
  DetectorModelOptions detector;

  // Print progress.
  bool show_progress = true;

  // The clean preset: plain paint, no street clutter, no sway, 3DOP-like
  // white detection noise, no false positives.
  static SynthOptions Clean();
  void Check() const;
  std::string ToJson() const;
};

struct SynthSequenceInfo {
  std::string name;        // 6 digits
  std::string folder;
  int num_cars = 0;
  int num_detections = 0;  // over all frames
  int num_gt_labels = 0;   // car-frames with at least one visible pixel
  int num_false_positives = 0;
  // Disparity quality on the visible car pixels: mean absolute error (px) over
  // the valid pixels, and the share of car pixels with a valid disparity.
  double car_disparity_mae_px = 0.0;
  double car_disparity_valid_fraction = 0.0;
  int64_t car_pixels = 0;
};

}  // namespace samp
