// The errors of a stereo 3D car detector (3DOP-like, docs/synthetic.md "Detector
// model"), applied to true boxes: position error growing with distance and
// largest along the viewing ray, vertical, size and yaw errors, 180-degree
// flips, misses and false positives on clutter, all temporally correlated
// (a detector errs the same way for a few frames).
//
// Independent of the renderer: it turns true KITTI labels into detections, so
// it can be tested and reused on its own (tests/synth/detector_model_test.cc).
// Deterministic: every track has its own random stream seeded from (seed,
// track id), so the detections of one car do not depend on the other cars.
// Not thread-safe (one instance per sequence).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "libsamp/core/camera.h"
#include "libsamp/data/detector_noise.h"
#include "libsamp/data/image_box.h"
#include "libsamp/data/track.h"

namespace samp {

struct DetectorModelOptions {
  // The named profile these options came from (DetectorProfile; "" = the
  // preset's own detector). Only a record: the fields below are what is drawn.
  std::string profile;
  // Std. dev. of the position error along the horizontal viewing ray,
  // a + b d + c d^2 metres at distance d (defaults: 0.29 m at 10 m, 0.73 m at 45 m).
  double ray_sigma_a = 0.16, ray_sigma_b = 0.013, ray_sigma_c = 0.0;
  // Std. dev. of the horizontal position error across the ray, a + b d metres.
  double lateral_sigma_a = 0.05, lateral_sigma_b = 0.004;
  // Std. dev. of the vertical position error (camera y), metres.
  double vertical_sigma = 0.25;
  // Std. dev. of each box dimension h, w, l: size_sigma metres + relative_size_sigma x the true size.
  double size_sigma = 0.3;
  double relative_size_sigma = 0.0;
  // Systematic error of each box dimension, detected - true, metres (e.g.
  // KITTI-convention boxes exclude the mirrors: width 0.2-0.3 m narrower than
  // the CAD extent). Added before the noise.
  double height_bias = 0.0, width_bias = 0.0, length_bias = 0.0;
  // Systematic error of the bottom centre along the horizontal viewing ray,
  // metres (+ = farther than the truth). Added to the noise along the ray.
  double along_ray_bias = 0.0;
  // Std. dev. of the yaw error, a + b d degrees.
  double yaw_sigma_deg_a = 3.0, yaw_sigma_deg_b = 0.05;
  // Share of detections turned by 180 degrees and its mean run length in frames
  // (a two-state Markov chain per track; 0 = independent per frame).
  double flip_probability = 0.065;
  double flip_mean_run_frames = 4.0;
  // Share of visible cars missed and the mean run length of a miss (0 = independent).
  double miss_probability = 0.05;
  double miss_mean_run_frames = 2.0;
  // Time constant (frames) of the AR(1) process of the continuous errors
  // (position, size, yaw): correlation exp(-1 / tau) between consecutive frames; 0 = white.
  double correlation_frames = 3.0;
  // Mean number of false positives per frame (on the clutter candidates the scene
  // offers: poles, trees, bins, walls, facades, parked rows) and their mean lifetime (frames).
  double false_positives_per_frame = 0.3;
  double false_positive_mean_run_frames = 3.0;
  // Std. dev. of the 2D box corners, px (independent per frame).
  double box_sigma_px = 2.0;
  // Cars with fewer visible pixels are never detected.
  int min_pixels = 150;

  void Check() const;  // throws samp::Error naming the field
};

// The errors of one detection relative to its true box (for tests and diagnostics).
struct DetectionError {
  double along_ray = 0.0, lateral = 0.0, vertical = 0.0;  // metres (along_ray includes along_ray_bias)
  double yaw_rad = 0.0;                                    // without the flip
  bool flipped = false;
};

// A place where the detector may fire without a car: a car-sized box standing
// on the road near clutter, in the camera of the frame. `id` is stable over
// the frames (a false positive sticks to its candidate while it lives).
struct ClutterCandidate {
  int id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // bottom centre, camera frame
  double rotation_y = 0.0;
  double height = 1.5, width = 1.8, length = 4.2;
};

class StereoDetectorModel {
 public:
  // Throws samp::Error when the options are invalid.
  StereoDetectorModel(const DetectorModelOptions& options, uint64_t seed);
  ~StereoDetectorModel();

  // The detection of one true car at one frame. Call per track in increasing
  // frame order (frames may be skipped: the correlated state decays over the
  // gap). Draws the errors whether or not the car is detected, so a miss does
  // not change later detections. Returns false when the car is missed or has
  // fewer than min_pixels visible pixels; `error` (optional) gets the drawn errors.
  bool Detect(int track_id, int frame, const ObjectLabel& truth, int visible_pixels,
              const PinholeCamera& camera, ObjectLabel* detection, DetectionError* error = nullptr);

  // False positives of one frame, on candidates whose box projects into the
  // image. Call once per frame in increasing frame order.
  std::vector<ObjectLabel> FalsePositives(int frame, const std::vector<ClutterCandidate>& candidates,
                                          const PinholeCamera& camera);

  const DetectorModelOptions& options() const { return options_; }

 private:
  struct TrackState;
  struct FalsePositiveState {
    int candidate_id = 0;
    double along = 0.0, lateral = 0.0, yaw = 0.0;  // offsets of this false positive
  };
  TrackState& State(int track_id);

  DetectorModelOptions options_;
  uint64_t seed_;
  std::map<int, std::unique_ptr<TrackState>> tracks_;
  std::mt19937_64 clutter_engine_;
  std::vector<FalsePositiveState> alive_;
};

// Named detector profiles (docs/synthetic.md, "Detector profiles"), each a
// DetectorModelOptions with `profile` set to its name:
//   default      the stereo detector above (DetectorModelOptions(); the same draws)
//   lidar        position, size and yaw sigmas x 0.25 (a LiDAR-grade detector)
//   stereo-x2    position, size and yaw sigmas x 2
//   size-x3      box size sigmas x 3
//   kitti-boxes  KITTI-convention boxes: width 0.25 m narrower than the CAD
//                extent (mirrors excluded), bottom centre 0.2 m nearer along the ray
//   flips        8 % of the detections turned by 180 degrees, each flip one frame long
// Throws samp::Error naming the profile and listing the known ones.
DetectorModelOptions DetectorProfile(const std::string& name);
const std::vector<std::string>& DetectorProfileNames();

// The mean and standard deviation of max(floor, mean + sigma z), z standard
// normal: a detected box dimension's error, which the detector clips at minus
// half the true size (StereoDetectorModel::Detect). Throws samp::Error on
// non-finite arguments or sigma < 0.
struct ClippedNormalMoments {
  double mean = 0.0, sigma = 0.0;
};
ClippedNormalMoments ClippedNormal(double mean, double sigma, double floor);

// The true noise model of a synthetic detector in the format of the
// self-calibration and `samp calibrate-detector` (data/detector_noise.h), so
// that a fit can be given it (`samp fit --detector-model`). The format's
// position sigmas are a + b d in the horizontal distance, its yaw sigma one
// number and its errors white; where the options are richer the conversion
// approximates over cars at [min_distance, max_distance] m and says so in the
// model's notes: the along-ray term's c d^2 by the least-squares line, the yaw
// sigma a + b d by its root mean square, a relative size sigma at a typical car
// box (h 1.5, w 1.8, l 4.3 m), and the size sigmas and biases are those of
// the errors clipped at half that box (ClippedNormal: size-x3's width sigma
// is 0.78 m, not 0.9; the default's are within 1 % of 0.3 m); the vertical
// sigma is constant (b = 0). Position biases are the options'
// (biases_estimated = true); flip, miss and false-positive rates are the
// options' stationary shares. Sample counts are 0 (no samples:
// the values are the generating ones). Throws samp::Error on invalid options
// or distances.
DetectorNoiseModel TrueDetectorNoiseModel(const DetectorModelOptions& options, double min_distance,
                                          double max_distance);

}  // namespace samp
