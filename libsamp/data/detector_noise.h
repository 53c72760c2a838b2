// The detector's noise model, measured from the data (docs/detector_calibration.md):
// how a 3D car detector errs in the bottom centre (along the horizontal viewing
// ray, across it, vertically; each a function of the distance), in each box
// dimension, in yaw modulo 180 degrees, and how often it flips a box, misses a
// car or fires without one.
//
// Two estimators fill the same DetectorNoiseModel:
//  - EstimateDetectorNoise: self-calibration from linked tracks, no ground
//    truth. Each confident track is smoothed over the whole sequence (samp is
//    offline): a robust (iteratively reweighted, Tukey) polynomial in time of
//    the bottom centre in the world, the median box, the mean axis; its
//    detections' residuals give the sigmas, corrected for what the smoother
//    absorbs of errors correlated in time (residual_correlation.h). Biases are not observable this way
//    (they are reported as 0 and `biases_estimated` is false).
//  - EstimateDetectorNoiseFromTruth: detections matched to ground-truth boxes
//    (`samp calibrate-detector`): sigmas and biases.
// Both use robust statistics: a median centre and a 3-sigma trimmed standard
// deviation started from the MAD, corrected for the trimming, so flips,
// misses, false positives and wrong boxes do not inflate the sigmas.
// CalibrateTracker links, estimates and re-links to a fixed point.
//
// The model's JSON (WriteDetectorNoiseModel / ReadDetectorNoiseModel) is owned
// here: {"format": "samp-detector-model", "version": 1, ...}; every field is
// checked when read and errors name the file and the key.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "libsamp/data/sequence.h"
#include "libsamp/data/tracking.h"

namespace samp {

// Residual statistics of one distance bin [min_distance, max_distance) (m).
struct DistanceBin {
  double min_distance = 0.0, max_distance = 0.0;
  int count = 0;  // detections in the bin
  // The tracks (self-calibration) or true cars they belong to; 0 = not
  // recorded (a file written without it).
  int tracks = 0;
  // Their mean horizontal distance (m): where the bin's sigmas enter the
  // a + b d fit. 0 = not recorded (a file written without it).
  double mean_distance = 0.0;
  // Robust std. dev. and bias (median) of the position error (m).
  double along_sigma = 0.0, across_sigma = 0.0, vertical_sigma = 0.0;
  double along_bias = 0.0, across_bias = 0.0, vertical_bias = 0.0;
};

struct DetectorNoiseModel {
  static constexpr int kVersion = 1;
  // "self-calibration", "ground truth" or "defaults" (too few samples).
  std::string source = "defaults";
  // Position error std. dev. (m) at horizontal distance d: along the ray
  // along_sigma_a + along_sigma_b d, across it across_sigma_a + across_sigma_b
  // d, vertically vertical_sigma_a + vertical_sigma_b d (TrackerOptions' form).
  double along_sigma_a = 0.25, along_sigma_b = 0.015;
  double across_sigma_a = 0.1, across_sigma_b = 0.005;
  double vertical_sigma_a = 0.2, vertical_sigma_b = 0.002;
  // Centre of the position error along the ray (m; ground truth only): the
  // distance bins' robust centres weighted by their inverse variances.
  double along_bias = 0.0;
  // Per box dimension h, w, l: std. dev. and bias (detected - true, m).
  double size_sigma[3] = {0.3, 0.3, 0.3};
  double size_bias[3] = {0.0, 0.0, 0.0};
  // Std. dev. of the yaw error modulo 180 degrees (deg).
  double yaw_sigma_deg = 10.0;
  // Share of detections turned by 180 degrees; share of a car's frames
  // without its detection; false positives per frame.
  double flip_rate = 0.0, miss_rate = 0.0, false_positives_per_frame = 0.0;
  bool biases_estimated = false;
  // The box convention as self-calibration measures it (EstimateBoxConvention):
  // size_bias and along_bias are then the detector's box minus the fitted
  // shape's extent and position; the counts of cars and detections used and
  // the standard errors. In the JSON as "box_convention" only when measured.
  bool box_convention_estimated = false;
  int box_convention_tracks = 0, box_convention_detections = 0;
  double size_bias_error[3] = {0.0, 0.0, 0.0};
  double along_bias_error = 0.0;
  // The correlation of the errors between consecutive frames per cue (along,
  // across, vertical, height, width, length, yaw), as self-calibration measured
  // it and corrected the residuals' shrinkage with (residual_correlation.h);
  // the fewest lag-1 pairs behind a cue. `correlation_shared`: too few pairs
  // per cue for a value of its own (DetectorNoiseOptions::
  // correlation_pairs_per_cue), so every cue has the one value measured on
  // all cues' residuals together, and `correlation_pairs` counts those. In the
  // JSON as "correlation" only when measured (from at least 30 pairs).
  bool correlation_estimated = false;
  double correlation[7] = {0, 0, 0, 0, 0, 0, 0};
  int correlation_pairs = 0;
  bool correlation_shared = false;
  // The time constant (frames) of the mean measured correlation, -1 / ln rho
  // (0: white), for FitOptions::detection_correlation_frames.
  double CorrelationFrames() const;
  // Sample counts: detections used for the position, size and yaw terms,
  // tracks (or true cars), frames.
  int num_position_samples = 0, num_size_samples = 0, num_yaw_samples = 0;
  int num_tracks = 0, num_frames = 0;
  // Ground truth only: detections without a true box that were not counted
  // as false positives because they lie in a DontCare region of their frame
  // (DetectorCalibrationOptions::dont_care_overlap). In the JSON as
  // "samples.dont_care_ignored" only when not 0.
  int num_dont_care_ignored = 0;
  std::vector<DistanceBin> bins;
  // Why a term kept its default ("too few ...").
  std::vector<std::string> notes;

  // Root mean square of the three size sigmas (the tracker's and the fitter's single size sigma).
  double MeanSizeSigma() const;
  // Sets the detector noise fields of `tracker` (the sigmas; the gates and the
  // motion model stay).
  void ApplyTo(TrackerOptions* tracker) const;
  std::string BriefReport() const;
  std::string ToJson() const;  // the file's contents
};

// Throws samp::Error naming `source` (a file) and the key when the JSON is
// malformed, of another format or version, or a value is out of range.
DetectorNoiseModel DetectorNoiseModelFromJson(const std::string& text, const std::string& source);
void WriteDetectorNoiseModel(const std::string& path, const DetectorNoiseModel& model);
DetectorNoiseModel ReadDetectorNoiseModel(const std::string& path);

struct DetectorNoiseOptions {
  // Tracks with fewer detections are not used (smoothing needs a few).
  int min_track_detections = 6;
  // Distance bin edges (m), increasing; the last bin is open.
  std::vector<double> bin_edges = {0, 10, 20, 30, 40, 60};
  // A bin with fewer detections does not enter the sigma(d) fit.
  int min_bin_count = 10;
  // ... or detections of fewer tracks (true cars): one car's errors are
  // correlated in time and its own (a persistent false positive far beyond
  // the cars, tracked with a steady box, reads as a tiny sigma there and
  // pulls the slope of sigma(d) to 0).
  int min_bin_tracks = 3;
  // Fewer samples for a term: that term keeps its default, with a note.
  int min_samples = 30;
  // Degree of the robust smoother of a track's bottom centre in time (1 =
  // constant velocity, 2 = constant acceleration for tracks of at least
  // 3 x (degree + 1) detections).
  int smoother_degree = 2;
  // Cut-off of the residuals (robust sigmas) that enter the trimmed statistics.
  double trim_sigmas = 3.0;
  // Measure how the errors are correlated between frames and undo the
  // smoother's shrinkage of correlated residuals (off: white, n - q).
  bool correct_correlation = true;
  // A cue gets a correlation of its own when every cue has at least this many
  // lag-1 pairs; with fewer the per-cue estimates scatter by about 0.1-0.2
  // and the correction is steep near rho = 1, so one correlation is measured
  // on all cues' residuals (each on its robust scale) together.
  int correlation_pairs_per_cue = 1000;

  void Check() const;  // throws samp::Error naming the field
};

// The detections and linked tracks of one sequence, for EstimateDetectorNoise.
struct LinkedSequence {
  std::vector<FrameDetections> frames;   // every frame, with its ego pose
  std::vector<LinkedTrack> tracks;
  int num_detections = 0;                // all detections of the frames (tracks or not)
};

// Self-calibration from linked tracks of one or more sequences (pooled).
// `defaults` gives each term's value when it has too few samples (noted).
DetectorNoiseModel EstimateDetectorNoise(const std::vector<LinkedSequence>& sequences,
                                         const DetectorNoiseOptions& options, const TrackerOptions& defaults);

// The box convention (docs/detector_calibration.md, "Box conventions"): how a
// detector's boxes differ on average from the shape model's extents (KITTI's
// exclude the mirrors that CAD extents include) and positions. Measured on
// near, well-observed cars: each is fitted to its points alone (no detection
// terms), and the fitted shape's inside box and origin are compared with the
// car's detections. One sample per such detection:
struct BoxConventionSample {
  int car = 0;                          // groups one car's detections (unique over the run)
  double distance = 0.0;                // horizontal distance of the detection, m
  int num_points = 0;                   // stereo points associated with the car in that frame
  double detected[3] = {0, 0, 0};       // the box's h, w, l, m
  double fitted[3] = {0, 0, 0};         // the fitted shape's inside box h, w, l, m
  double along = 0.0;                   // detected - fitted bottom centre along the horizontal ray, m
  // Angle between the car's length axis and its horizontal viewing ray, in
  // [0, 90] degrees: 0 = seen from behind or in front, 90 = from the side.
  double view_angle_deg = 0.0;
};

struct BoxConventionOptions {
  // A detection is used when its car is within this horizontal distance (m) ...
  double max_distance = 20.0;
  // ... and at least this many stereo points were associated in its frame.
  int min_points = 200;
  // The estimate needs this many cars and detections, else the biases stay 0 (noted).
  int min_cars = 3;
  int min_detections = 20;
  // A dimension is compared only where the points observe it: the width when
  // the car's rear or front faces the camera (view angle <= this), ...
  double max_end_view_deg = 60.0;
  // ... the length when its side does (view angle >= this); the height and the
  // position always.
  double min_side_view_deg = 30.0;
  // A bias smaller than this many standard errors is taken as 0 (noted).
  double min_significance = 2.0;
  // Apply the along-ray bias to the fit (it is always measured and reported).
  // Off by default: a fit to stereo points alone has its own along-ray bias
  // (SGBM's foreground fattening pulls it towards the camera), which this
  // estimate cannot tell from the detector's (docs/detector_calibration.md).
  bool apply_along_bias = false;
  void Check() const;  // throws samp::Error naming the field
};

// Sets model->size_bias, along_bias, their errors and counts and
// box_convention_estimated from the samples that pass the options' gates:
// per car the median difference, then over the cars the median, with the
// standard error 1.253 x 1.4826 MAD / sqrt(cars) (the cars are the independent
// samples: a car's detections share its fitted shape); the width and length
// only from the detections whose view observes them. Too few cars or
// detections (overall, or for one dimension), or an insignificant bias: 0 and
// a note. Returns the number of samples used.
int EstimateBoxConvention(const std::vector<BoxConventionSample>& samples, const BoxConventionOptions& options,
                          DetectorNoiseModel* model);

// A detection and its true box (camera frame of its frame); truth_id groups a car.
struct MatchedDetection {
  ObjectLabel detection, truth;
  int truth_id = 0;
};

// Calibration against ground truth: `matches` are detections with their true
// boxes, `num_missed` true boxes without a detection, `num_false_positives`
// detections without a true box, over `num_frames` frames. `match_distance`:
// the horizontal distance (m) within which the matches were made (infinity:
// no gate). The gate cuts the error's tails, unevenly when the detector is
// biased; the statistics keep their windows inside it, so the along-ray bias
// and the far bins' sigmas are not pulled towards 0 by it.
DetectorNoiseModel EstimateDetectorNoiseFromTruth(
    const std::vector<MatchedDetection>& matches, int num_missed, int num_false_positives, int num_frames,
    const DetectorNoiseOptions& options, const TrackerOptions& defaults,
    double match_distance = std::numeric_limits<double>::infinity());

// Self-calibrating tracking: link with robust cues (and `initial`'s sigmas),
// estimate the noise model from all sequences, re-link with it, until the
// sigmas change by less than `tolerance` (relative) or after max_iterations.
struct CalibrationOptions {
  DetectorNoiseOptions noise;
  int max_iterations = 4;
  double tolerance = 0.05;
  // The tracker's sigmas are the estimate times this (>= 1: the tracker's
  // filter assumes white noise, a detector's errors are correlated in time).
  double tracker_sigma_scale = 1.25;
  // samp fit (`--estimate-box-convention`): estimate the box convention
  // (EstimateBoxConvention) from a first fit of the near, well-observed cars
  // to their points alone, and refit every car with it. Off by default: on
  // the street benchmark's SGBM sequences those points-only fits are
  // themselves ~0.2 m off in width, length and along the ray, which the
  // estimate cannot tell from the detector's convention (measured in
  // docs/detector_calibration.md, "Box conventions").
  bool estimate_box_convention = false;
  BoxConventionOptions box;
  void Check() const;
};

struct CalibrationResult {
  DetectorNoiseModel model;
  TrackerOptions tracker;  // `initial` with the estimate applied and robust_cues on
  int iterations = 0;
  bool converged = false;
  std::vector<std::string> history;  // one BriefReport per iteration
  std::string BriefReport() const;
};

// The tracker for a noise model: `initial` with the model's sigmas times
// `sigma_scale` and robust cues on.
TrackerOptions TrackerForModel(const TrackerOptions& initial, const DetectorNoiseModel& model, double sigma_scale);

// `frames_of_sequence`: every sequence's frames (detections and ego poses).
CalibrationResult CalibrateTracker(const std::vector<std::vector<FrameDetections>>& frames_of_sequence,
                                   const TrackerOptions& initial, const CalibrationOptions& options);

// `samp calibrate-detector`: the detections of sequences (their layout's, or
// SequenceOptions::detections_path: e.g. a tracker's KITTI tracking result
// file, whose track ids are ignored) matched to ground-truth tracking labels
// (KITTI label_02 format) frame by frame: a minimum-cost assignment on the
// horizontal distance of the bottom centres, pairs within match_distance.
// A detection left without a true box is a false positive unless its box,
// projected into the left image, lies in the frame's DontCare regions (KITTI
// label_02's DontCare lines: image areas that were not labelled).
struct DetectorCalibrationOptions {
  std::vector<std::string> sequences;
  // One KITTI tracking label file per sequence; empty = SEQ/gt/label_02/<seq>.txt
  // (samp's layout) or ROOT/label_02/<seq>.txt (KITTI tracking's, ROOT/image_02/<seq>).
  std::vector<std::string> truth_labels;
  // Object types, minimum score, frame range and the detections:
  // detections_path (a file only with one sequence, else a folder of
  // <seq>.txt) and detection_format; tracking_labels_path must be empty.
  SequenceOptions sequence;
  double match_distance = 3.0;   // m
  // A detection without a true box is ignored (neither matched nor a false
  // positive; counted in DetectorNoiseModel::num_dont_care_ignored) when at
  // least this share of its projected 2D box, and some of it, lies inside
  // the union of its frame's DontCare boxes; in [0, 1] (1: wholly inside).
  double dont_care_overlap = 0.5;
  DetectorNoiseOptions noise;
  TrackerOptions defaults;       // the values of terms with too few samples
  void Check() const;            // throws samp::Error naming the field
};

struct DetectorCalibrationSummary {
  int num_detections = 0, num_truths = 0, num_matched = 0, num_frames = 0;
  int num_dont_care_ignored = 0;  // unmatched detections in DontCare regions (not false positives)
  std::string BriefReport() const;
};

// Throws samp::Error naming the file when a sequence, detection or label file
// cannot be read (a malformed line, a wrong column count: file and line), a
// label or detection file has entries in frames its sequence does not have
// (mismatched files), or fewer than noise.min_samples detections match.
DetectorNoiseModel CalibrateDetectorFromTruth(const DetectorCalibrationOptions& options,
                                              DetectorCalibrationSummary* summary = nullptr);

}  // namespace samp
