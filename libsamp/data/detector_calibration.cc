// The fixed point of tracking and self-calibration (CalibrateTracker) and the
// calibration from ground-truth labels behind `samp calibrate-detector`
// (CalibrateDetectorFromTruth); the model and its estimators are in
// detector_noise.cc. Declared in data/detector_noise.h.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <vector>

#include "libsamp/core/assignment.h"
#include "libsamp/core/error.h"
#include "libsamp/data/calibration_option_table.h"
#include "libsamp/data/detector_noise.h"
#include "libsamp/data/image_box.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/kitti_tracking.h"
#include "libsamp/data/sequence_layout.h"

namespace samp {

void CalibrationOptions::Check() const {
  CalibrationOptionTable().Check(*this);
  noise.Check();  // the bin edges
}

std::string CalibrationResult::BriefReport() const {
  std::ostringstream s;
  s << "detector self-calibration: " << iterations << " iteration(s), "
    << (converged ? "converged" : "not converged") << "; " << model.BriefReport();
  return s.str();
}

TrackerOptions TrackerForModel(const TrackerOptions& initial, const DetectorNoiseModel& model, double k) {
  SAMP_CHECK(k > 0) << "TrackerForModel: sigma_scale must be > 0";
  TrackerOptions next = initial;
  model.ApplyTo(&next);
  next.along_sigma_a *= k, next.along_sigma_b *= k, next.across_sigma_a *= k, next.across_sigma_b *= k;
  next.vertical_sigma_a *= k, next.vertical_sigma_b *= k, next.size_sigma *= k, next.yaw_sigma_deg *= k;
  next.robust_cues = true;
  next.Check();
  return next;
}

CalibrationResult CalibrateTracker(const std::vector<std::vector<FrameDetections>>& frames_of_sequence,
                                   const TrackerOptions& initial, const CalibrationOptions& options) {
  options.Check();
  initial.Check();
  CalibrationResult result;
  result.tracker = initial;
  result.tracker.robust_cues = true;
  DetectorNoiseModel previous;
  bool have_previous = false;
  for (int iteration = 1; iteration <= options.max_iterations; ++iteration) {
    std::vector<LinkedSequence> linked(frames_of_sequence.size());
    for (size_t s = 0; s < frames_of_sequence.size(); ++s) {
      linked[s].frames = frames_of_sequence[s];
      for (const FrameDetections& f : linked[s].frames) linked[s].num_detections += int(f.detections.size());
      if (linked[s].frames.empty()) continue;
      linked[s].tracks = LinkDetections(linked[s].frames, result.tracker, nullptr);
    }
    // The residuals are weighted by the current model (the tracker's, without its safety scale).
    TrackerOptions weighting = initial;
    if (have_previous) previous.ApplyTo(&weighting);
    DetectorNoiseModel model = EstimateDetectorNoise(linked, options.noise, weighting);
    // Terms with too few samples keep the user's values, not the previous iteration's.
    if (model.num_position_samples < options.noise.min_samples) {
      model.along_sigma_a = initial.along_sigma_a, model.along_sigma_b = initial.along_sigma_b;
      model.across_sigma_a = initial.across_sigma_a, model.across_sigma_b = initial.across_sigma_b;
      model.vertical_sigma_a = initial.vertical_sigma_a, model.vertical_sigma_b = initial.vertical_sigma_b;
    }
    if (model.num_size_samples < options.noise.min_samples)
      for (double& s : model.size_sigma) s = initial.size_sigma;
    if (model.num_yaw_samples < options.noise.min_samples) model.yaw_sigma_deg = initial.yaw_sigma_deg;
    result.iterations = iteration;
    result.history.push_back(model.BriefReport());
    double change = have_previous ? 0.0 : 1e9;
    if (have_previous) {
      auto relative = [](double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-3); };
      // Sigma at 10 and 40 m for the position terms.
      for (double d : {10.0, 40.0}) {
        change = std::max(change, relative(model.along_sigma_a + model.along_sigma_b * d,
                                           previous.along_sigma_a + previous.along_sigma_b * d));
        change = std::max(change, relative(model.across_sigma_a + model.across_sigma_b * d,
                                           previous.across_sigma_a + previous.across_sigma_b * d));
        change = std::max(change, relative(model.vertical_sigma_a + model.vertical_sigma_b * d,
                                           previous.vertical_sigma_a + previous.vertical_sigma_b * d));
      }
      for (int i = 0; i < 3; ++i) change = std::max(change, relative(model.size_sigma[i], previous.size_sigma[i]));
      change = std::max(change, relative(model.yaw_sigma_deg, previous.yaw_sigma_deg));
    }
    previous = model;
    have_previous = true;
    result.tracker = TrackerForModel(initial, model, options.tracker_sigma_scale);
    result.model = model;
    if (change < options.tolerance) {
      result.converged = true;
      break;
    }
  }
  return result;
}

void DetectorCalibrationOptions::Check() const {
  SAMP_CHECK(!sequences.empty()) << "DetectorCalibrationOptions.sequences is empty (give at least one --seq)";
  SAMP_CHECK(truth_labels.empty() || truth_labels.size() == sequences.size())
      << "DetectorCalibrationOptions.truth_labels: " << truth_labels.size() << " files for " << sequences.size()
      << " sequences (give none or one per sequence)";
  SAMP_CHECK(match_distance > 0) << "DetectorCalibrationOptions.match_distance must be > 0";
  SAMP_CHECK(std::isfinite(dont_care_overlap) && dont_care_overlap >= 0 && dont_care_overlap <= 1)
      << "DetectorCalibrationOptions.dont_care_overlap (--dont-care-overlap) must be in [0, 1] (the share of a "
         "detection's 2D box inside DontCare regions), got "
      << dont_care_overlap;
  std::error_code error;
  SAMP_CHECK(sequence.detections_path.empty() || sequences.size() == 1 ||
             std::filesystem::is_directory(sequence.detections_path, error))
      << "DetectorCalibrationOptions.sequence.detections_path (--detections) " << sequence.detections_path
      << " is a file, but " << sequences.size()
      << " sequences are calibrated: give a folder with <seq>.txt per sequence";
  SAMP_CHECK(sequence.tracking_labels_path.empty())
      << "DetectorCalibrationOptions.sequence.tracking_labels_path must be empty: the detector is calibrated on "
         "detections, not tracks";
  sequence.Check();
  noise.Check();
  defaults.Check();
}

std::string DetectorCalibrationSummary::BriefReport() const {
  std::ostringstream s;
  s << num_frames << " frames: " << num_detections << " detections, " << num_truths << " true boxes, "
    << num_matched << " matched";
  if (num_dont_care_ignored > 0) s << ", " << num_dont_care_ignored << " unmatched in DontCare regions ignored";
  return s.str();
}

namespace {

// The ground truth beside a sequence: SEQ/gt/label_02/<seq>.txt (samp's
// layout, as `samp synth` writes it) or ROOT/label_02/<seq>.txt (KITTI
// tracking's); KITTI stereo's layout has none.
std::string DefaultTruthLabels(const SequenceFiles& files) {
  if (files.layout == SequenceFiles::Layout::kKittiTracking) {
    KittiTrackingLayout layout("", "");
    SAMP_CHECK(KittiTrackingLayout::FromSequenceFolder(files.directory, &layout))
        << files.directory << ": not a KITTI tracking sequence folder ROOT/image_02/<seq>";
    return layout.Labels();
  }
  SAMP_CHECK(files.layout == SequenceFiles::Layout::kSamp)
      << "sequence " << files.directory << " has no tracking labels of its own layout: give --labels";
  return SequenceLayout(files.directory, files.name).GroundTruthLabels();
}

}  // namespace

DetectorNoiseModel CalibrateDetectorFromTruth(const DetectorCalibrationOptions& options,
                                              DetectorCalibrationSummary* summary) {
  options.Check();
  DetectorCalibrationSummary local;
  DetectorCalibrationSummary& result = summary != nullptr ? *summary : local;
  result = DetectorCalibrationSummary();
  std::vector<MatchedDetection> matches;
  int num_missed = 0, num_false_positives = 0;
  for (size_t s = 0; s < options.sequences.size(); ++s) {
    const SequenceReader reader(options.sequences[s], options.sequence);
    const SequenceFiles& files = reader.files();
    const std::string labels_path =
        options.truth_labels.empty() ? DefaultTruthLabels(files) : options.truth_labels[s];
    // The labels are in the layout's label frame (KITTI: rectified camera 0),
    // the detections the reader gives in the camera's.
    const Eigen::Vector3d camera_from_label_frame = -reader.label_frame_offset();
    std::map<int, std::vector<ObjectLabel>> truth_of_frame;
    std::map<int, std::vector<Eigen::Vector4d>> dont_care_of_frame;  // 2D boxes in the left image, px
    std::map<int, int> index_of_frame;
    for (int i = 0; i < reader.num_frames(); ++i) index_of_frame[files.frames[i].frame] = i;
    auto in_range = [&](int frame) {
      return (options.sequence.first_frame < 0 || frame >= options.sequence.first_frame) &&
             (options.sequence.last_frame < 0 || frame <= options.sequence.last_frame);
    };
    for (const ObjectLabel& label : ReadTrackingLabels(labels_path)) {
      if (SameObjectType(label.type, "DontCare")) {
        // Regions of the image that were not labelled; those of frames the sequence does not have are
        // left out (a car's label there is an error below).
        if (in_range(label.frame) && index_of_frame.count(label.frame) > 0)
          dont_care_of_frame[label.frame].push_back(label.box_2d);
        continue;
      }
      bool kept = false;
      for (const std::string& type : options.sequence.object_types) kept = kept || SameObjectType(label.type, type);
      if (!kept || !in_range(label.frame)) continue;
      SAMP_CHECK(index_of_frame.count(label.frame) > 0)
          << labels_path << ": a label in frame " << label.frame << ", which sequence " << options.sequences[s]
          << " does not have (mismatched label file?)";
      truth_of_frame[label.frame].push_back(MoveLabel(label, camera_from_label_frame));
    }
    for (const auto& [frame, index] : index_of_frame) {
      if (!in_range(frame)) continue;
      ++result.num_frames;
      const std::vector<ObjectLabel> detections = reader.ReadDetections(index);
      const std::vector<ObjectLabel>& truths = truth_of_frame[frame];
      result.num_detections += int(detections.size());
      result.num_truths += int(truths.size());
      const int rows = int(detections.size()), cols = int(truths.size());
      std::vector<double> cost(size_t(rows) * cols, kNoAssignment);
      for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c) {
          const Eigen::Vector3d d = detections[r].position - truths[c].position;
          const double horizontal = std::hypot(d.x(), d.z());
          if (horizontal <= options.match_distance) cost[size_t(r) * cols + c] = horizontal;
        }
      const std::vector<int> assignment = SolveAssignment(cost, rows, cols);
      int matched = 0, ignored = 0;
      const auto dont_care = dont_care_of_frame.find(frame);
      for (int r = 0; r < rows; ++r) {
        if (assignment[r] < 0) {
          // Without a true box: a false positive unless it lies in the frame's DontCare regions.
          Eigen::Vector4d box;
          if (dont_care != dont_care_of_frame.end() && ProjectBox(detections[r], reader.calibration().camera, &box)) {
            const double share = AreaShareInside(box, dont_care->second);
            if (share > 0 && share >= options.dont_care_overlap) ++ignored;
          }
          continue;
        }
        MatchedDetection m;
        m.detection = detections[r];
        m.truth = truths[assignment[r]];
        m.truth_id = int(s) * 1000000 + m.truth.track_id;
        matches.push_back(m);
        ++matched;
      }
      num_false_positives += rows - matched - ignored;
      num_missed += cols - matched;
      result.num_dont_care_ignored += ignored;
    }
  }
  result.num_matched = int(matches.size());
  SAMP_CHECK(result.num_matched >= options.noise.min_samples)
      << "calibrate-detector: only " << result.num_matched << " detection(s) match a true box within "
      << options.match_distance << " m (" << result.BriefReport() << "); at least " << options.noise.min_samples
      << " are needed: give more sequences, or check that the labels belong to the sequences";
  DetectorNoiseModel model = EstimateDetectorNoiseFromTruth(matches, num_missed, num_false_positives,
                                                            result.num_frames, options.noise, options.defaults,
                                                            options.match_distance);
  model.num_dont_care_ignored = result.num_dont_care_ignored;
  return model;
}

}  // namespace samp
