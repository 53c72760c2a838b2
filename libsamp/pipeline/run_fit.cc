#include "libsamp/pipeline/run_fit.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/core/ply_io.h"
#include "libsamp/core/pose.h"
#include "libsamp/pipeline/fit_config.h"
#include "libsamp/pipeline/fit_output.h"
#include "libsamp/pipeline/run_fit_option_table.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/sequence.h"
#include "libsamp/model/shape_model.h"

namespace samp {

namespace fs = std::filesystem;

void RunFitOptions::Check() const {
  RunFitOptionTable().Check(*this);
  fit.Check();
  sequence.Check();
  calibration.Check();
}

std::string RunFitSummary::BriefReport() const {
  std::ostringstream s;
  s << sequences.size() << " sequence(s) (" << num_sequences_failed << " failed), "
    << num_tracks_fitted << " track(s) fitted, " << num_tracks_failed << " failed, " << seconds
    << " s";
  if (seconds_calibration > 0) s << " (self-calibration " << seconds_calibration << " s)";
  for (const auto& q : sequences) {
    s << "\n  " << (q.name.empty() ? q.directory : q.name) << ": ";
    if (!q.ok) {
      s << "FAILED: " << q.error;
      continue;
    }
    s << q.num_fitted << "/" << q.num_tracks << " tracks";
    if (q.num_at_grid_limit > 0) s << " (" << q.num_at_grid_limit << " at the model grid's limits)";
    s << ", " << q.seconds << " s (frames "
      << q.input.seconds_frames << " s, tracking " << q.input.seconds_tracking << " s, fit " << q.seconds_fit
      << " s, output " << q.seconds_output << " s); tracker: " << q.input.tracking.BriefReport();
    for (const auto& f : q.track_failures) s << "\n    skipped " << f;
  }
  if (detector_model_used) s << "\n  detector model: " << calibration_report;
  return s.str();
}

namespace {

struct SequenceWork {
  SequenceFitResult result;
  std::vector<TracksFileTrack> tracks;  // for tracks.json
};

// Refuses an output folder that RunFit must not replace as a whole; true when
// it holds an earlier run (to be replaced). Inputs are compared by resolved
// path and by device and inode (core/atomic_file.h IsInsideFolder, SameFile),
// so a hard link, bind mount or symbolic link does not hide one.
bool CheckOutputFolder(const RunFitOptions& options) {
  const std::string& out_name = options.output_dir;
  const char* why = ": samp fit replaces its output folder as a whole at the end of the run";
  std::vector<std::pair<std::string, std::string>> inputs;  // what, path
  for (const std::string& seq : options.sequences) inputs.emplace_back("sequence", seq);
  for (const std::string& labels : options.tracking_labels) inputs.emplace_back("tracking label file", labels);
  if (!options.link_only) inputs.emplace_back("model", options.model_path);
  inputs.emplace_back("detections", options.sequence.detections_path);
  for (const auto& [what, path] : inputs) {
    SAMP_CHECK(path.empty() || !IsInsideFolder(path, out_name))
        << "output folder " << out_name << " holds the input " << what << " " << path << why
        << "; give an output folder outside the inputs";
  }
  std::error_code ec;
  const fs::path cwd = fs::current_path(ec);
  SAMP_CHECK(ec || !IsInsideFolder(cwd.string(), out_name))
      << "output folder " << out_name << " is the current folder or holds it" << why
      << "; give another folder";
  const bool earlier_run = CheckReplaceableOutputFolder(out_name, why);
  if (earlier_run) {
    // A file of the earlier run that is an input under another name (a hard link).
    for (fs::recursive_directory_iterator it(out_name, ec), end; !ec && it != end; it.increment(ec)) {
      for (const auto& [what, path] : inputs) {
        SAMP_CHECK(path.empty() || !SameFile(it->path().string(), path))
            << "output folder " << out_name << " holds the input " << what << " " << path << " as "
            << it->path().string() << why << "; give an output folder outside the inputs";
      }
    }
  }
  return earlier_run;
}

// Refuses two sequences whose outputs would have the same name.
void CheckSequenceNames(const RunFitOptions& options) {
  std::map<std::string, size_t> first;
  for (size_t i = 0; i < options.sequences.size(); ++i) {
    const std::string name = SequenceOutputName(options.sequences[i]);
    const auto [it, inserted] = first.emplace(name, i);
    SAMP_CHECK(inserted) << "sequences " << options.sequences[it->second] << " and " << options.sequences[i]
                         << " have the same name '" << name << "': their outputs (label_02/" << name
                         << ".txt, meshes/" << name << "/) would overwrite each other; fit them into "
                         << "separate output folders";
  }
}

std::string MeshPrefix(const RunFitOptions& options, const std::string& seq, int track_id) {
  return FitMeshStem(seq, track_id, options.sequences.size() > 1);
}

// Writes FOLDER/label_02/<seq>.txt, the labels by frame and then track id; a
// failure marks the sequence as failed.
void WriteSequenceLabels(const std::string& folder, std::vector<ObjectLabel> labels, SequenceFitResult* result) {
  LabelsInLayoutFrame(result->input, &labels);  // KITTI tracking: rectified camera 0 (data/sequence.h)
  std::stable_sort(labels.begin(), labels.end(), [](const ObjectLabel& a, const ObjectLabel& b) {
    return a.frame != b.frame ? a.frame < b.frame : a.track_id < b.track_id;
  });
  try {
    WriteTrackingLabels(FitLabelsPath(folder, result->name), labels);
  } catch (const std::exception& e) {
    result->ok = false;
    result->error = std::string("writing labels: ") + e.what();
  }
}

// fitter == nullptr: link only (the tracks' detections are the labels).
void FitSequence(const RunFitOptions& options, const std::string& folder, const TrackFitter* fitter,
                 size_t index, SequenceWork* work) {
  const auto start = std::chrono::steady_clock::now();
  SequenceFitResult& result = work->result;
  result.directory = options.sequences[index];
  std::vector<Track> tracks;
  try {
    SequenceOptions seq_options = options.sequence;
    if (!options.tracking_labels.empty()) seq_options.tracking_labels_path = options.tracking_labels[index];
    tracks = LoadSequenceTracks(result.directory, seq_options, &result.input);
    result.name = result.input.name;
    if (result.name.empty()) result.name = SequenceOutputName(result.directory);
  } catch (const std::exception& e) {
    result.ok = false;
    result.error = e.what();
    LogError() << "sequence " << result.directory << " skipped: " << e.what();
    return;
  }
  result.ok = true;
  result.num_tracks = int(tracks.size());
  if (fitter == nullptr) {
    std::vector<ObjectLabel> labels;
    for (const Track& track : tracks)
      for (const TrackFrame& frame : track.frames) {
        ObjectLabel label = frame.detection;
        label.frame = frame.frame;
        label.track_id = track.id;
        labels.push_back(label);
      }
    WriteSequenceLabels(folder, std::move(labels), &result);
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return;
  }
  std::vector<TrackFit> fits(tracks.size());
  std::vector<std::string> errors(tracks.size());
  const auto fit_start = std::chrono::steady_clock::now();
  tbb::parallel_for(size_t(0), tracks.size(), [&](size_t t) {
    try {
      fits[t] = fitter->Fit(tracks[t]);
      if (fits[t].sequence.empty()) fits[t].sequence = result.name;
    } catch (const std::exception& e) {
      errors[t] = e.what();
    }
  });
  const auto output_start = std::chrono::steady_clock::now();
  result.seconds_fit = std::chrono::duration<double>(output_start - fit_start).count();
  std::vector<ObjectLabel> labels;
  for (size_t t = 0; t < tracks.size(); ++t) {
    if (!errors[t].empty()) {
      result.track_failures.push_back("track " + std::to_string(tracks[t].id) + ": " + errors[t]);
      LogWarning() << result.name << ": track " << tracks[t].id << " skipped: " << errors[t];
      continue;
    }
    const std::string unusable = fits[t].summary.UnusableReason();
    if (!unusable.empty()) {
      // Ceres' result is not a solution: a failed track, not written as fitted.
      result.track_failures.push_back("track " + std::to_string(tracks[t].id) + ": " + unusable);
      LogWarning() << result.name << ": track " << tracks[t].id << " failed: " << unusable;
      continue;
    }
    try {
      const TrackFit& fit = fits[t];
      const std::vector<ObjectLabel> track_labels = FitToLabels(fit, tracks[t], fitter->lookup());
      TracksFileTrack record;
      record.box = FittedBox(fitter->lookup(), fit.shape_code);
      record.at_grid_limit = GridLimitsReached(record.box, fitter->lookup().grid());
      if (!record.at_grid_limit.empty()) {
        ++result.num_at_grid_limit;
        const Eigen::Vector3d size = record.box.max - record.box.min;
        std::ostringstream what;
        for (const std::string& a : record.at_grid_limit) what << (what.tellp() > 0 ? ", " : "") << a;
        what << std::fixed << std::setprecision(2) << " (l x h x w " << size.x() << " x " << size.y() << " x "
             << size.z() << " m)";
        LogWarning() << result.name << ": track " << fit.track_id << ": the fitted shape fills the model's grid in "
                     << what.str() << ": a vehicle the model does not span; its shape and pose are unreliable "
                     << "(docs/fitting.md, \"Shapes at the grid's limits\")";
      }
      if (options.write_meshes) {
        const std::string prefix = MeshPrefix(options, result.name, fit.track_id);
        const Mesh mesh = FittedSurface(fitter->lookup(), fit.shape_code);
        WritePly((fs::path(folder) / (prefix + ".ply")).string(), mesh);
        WritePly((fs::path(folder) / (prefix + "_points.ply")).string(),
                 AlignedObservations(fit));
        record.mesh = prefix + ".ply";
        record.points = prefix + "_points.ply";
      }
      record.fit = fit;
      for (FrameFit& f : record.fit.frames) f.points_in_world.clear();
      labels.insert(labels.end(), track_labels.begin(), track_labels.end());
      work->tracks.push_back(std::move(record));
      ++result.num_fitted;
      LogInfo() << result.name << ": track " << fit.track_id << " (" << fit.frames.size()
                << " frames): " << fit.summary.BriefReport();
    } catch (const std::exception& e) {
      result.track_failures.push_back("track " + std::to_string(tracks[t].id) + ": " + e.what());
      LogWarning() << result.name << ": track " << tracks[t].id << " output failed: " << e.what();
    }
  }
  WriteSequenceLabels(folder, std::move(labels), &result);
  const auto end = std::chrono::steady_clock::now();
  result.seconds_output = std::chrono::duration<double>(end - output_start).count();
  result.seconds = std::chrono::duration<double>(end - start).count();
}

// The detections and ego poses of a sequence's frames (in the options' frame
// range), for self-calibration.
std::vector<FrameDetections> ReadSequenceDetections(const std::string& directory, const SequenceOptions& options) {
  const SequenceReader reader(directory, options);
  std::vector<FrameDetections> frames;
  for (int i = 0; i < reader.num_frames(); ++i) {
    const int frame = reader.files().frames[i].frame;
    if ((options.first_frame >= 0 && frame < options.first_frame) ||
        (options.last_frame >= 0 && frame > options.last_frame))
      continue;
    FrameDetections fd;
    fd.frame = frame;
    fd.world_from_camera = reader.WorldFromCamera(frame);
    fd.detections = reader.ReadDetections(i);
    frames.push_back(std::move(fd));
  }
  return frames;
}

// Self-calibration or a detector model file: the options the run links and
// fits with (the tracker's sigmas, the fit's detection size sigma), and the
// model in the summary. Sequences that cannot be read or come with tracking
// labels do not take part (they fail or are linked later as before).
RunFitOptions CalibratedOptions(const RunFitOptions& options, RunFitSummary* summary) {
  RunFitOptions effective = options;
  if (!options.self_calibrate && options.detector_model_path.empty()) return effective;
  if (!options.detector_model_path.empty()) {
    summary->detector_model = ReadDetectorNoiseModel(options.detector_model_path);
    summary->calibration_report = "read from " + options.detector_model_path + ": " +
                                  summary->detector_model.BriefReport();
    effective.sequence.tracker = TrackerForModel(options.sequence.tracker, summary->detector_model,
                                                 options.calibration.tracker_sigma_scale);
  } else {
    std::vector<std::vector<FrameDetections>> frames;
    for (size_t i = 0; i < options.sequences.size(); ++i) {
      if (!options.tracking_labels.empty()) continue;
      try {
        frames.push_back(ReadSequenceDetections(options.sequences[i], options.sequence));
      } catch (const std::exception& e) {
        LogWarning() << "self-calibration: sequence " << options.sequences[i] << " left out: " << e.what();
      }
    }
    const CalibrationResult calibration = CalibrateTracker(frames, options.sequence.tracker, options.calibration);
    summary->detector_model = calibration.model;
    summary->calibration_report = calibration.BriefReport();
    effective.sequence.tracker = calibration.tracker;
    for (const std::string& note : calibration.model.notes)
      LogWarning() << "self-calibration: " << note << " (docs/detector_calibration.md)";
  }
  summary->detector_model_used = true;
  if (options.fit.detection_size_sigma > 0)
    effective.fit.detection_size_sigma = summary->detector_model.MeanSizeSigma();
  // How many independent observations a track's detections are worth, from the measured correlation.
  if (summary->detector_model.correlation_estimated)
    effective.fit.detection_correlation_frames = summary->detector_model.CorrelationFrames();
  LogInfo() << summary->calibration_report;
  return effective;
}

// tracks.json's record of the detector model the run linked and fitted with
// (CalibratedOptions, then the box convention): the run's one model, the
// same for each of its sequences.
TracksFileDetectorModel DetectorModelRecord(const RunFitOptions& options, const RunFitSummary& summary) {
  TracksFileDetectorModel record;
  if (!summary.detector_model_used) {
    record.origin = "none";
    record.reason =
        "self-calibration off and no detector model file: the tracker's and the fit's detector sigmas as "
        "given (config.json)";
  } else if (!options.detector_model_path.empty()) {
    record.origin = "file";
    record.file = options.detector_model_path;
  } else {
    record.origin = "self-calibration";
  }
  record.model = summary.detector_model;
  return record;
}

std::string BoxConventionReport(const DetectorNoiseModel& m, bool apply_along) {
  std::ostringstream s;
  s.precision(3);
  if (!m.box_convention_estimated) {
    s << "box convention not estimated (" << m.box_convention_tracks << " near cars, " << m.box_convention_detections
      << " detections): biases 0";
    return s.str();
  }
  s << "box convention (detected - shape) h/w/l " << m.size_bias[0] << "/" << m.size_bias[1] << "/" << m.size_bias[2]
    << " m (+- " << m.size_bias_error[0] << "/" << m.size_bias_error[1] << "/" << m.size_bias_error[2]
    << "), along-ray " << m.along_bias << " m (+- " << m.along_bias_error << (apply_along ? "" : "; measured, not applied")
    << "), from " << m.box_convention_tracks
    << " near cars, " << m.box_convention_detections << " detections";
  return s.str();
}

bool HasGivenBoxBias(const FitOptions& fit) {
  return fit.detection_length_bias != 0.0 || fit.detection_height_bias != 0.0 || fit.detection_width_bias != 0.0 ||
         fit.detection_along_bias != 0.0;
}

// The fit's detection terms with the model's box convention (detected box
// minus the shape's extent, along-ray offset), when it has one.
// The along-ray bias only when `apply_along` (BoxConventionOptions::apply_along_bias).
void ApplyBoxConvention(const DetectorNoiseModel& model, bool apply_along, FitOptions* fit) {
  if (!model.box_convention_estimated) return;
  fit->detection_height_bias = model.size_bias[0];
  fit->detection_width_bias = model.size_bias[1];
  fit->detection_length_bias = model.size_bias[2];
  if (apply_along) fit->detection_along_bias = model.along_bias;
}

// The box convention from the data (docs/detector_calibration.md, "Box
// conventions"): every sequence's near, well-observed cars (a frame within
// calibration.box.max_distance with at least min_points candidate points) are
// fitted to their points alone (no detection terms); their shapes' inside
// boxes and origins are compared with their detections (EstimateBoxConvention),
// which sets the model's biases. Sequences that cannot be read and tracks
// that fail are left out (they fail again, with their message, in the fit).
void EstimateRunBoxConvention(const RunFitOptions& options, const ShapeModel& shape_model, tbb::task_arena* arena,
                              DetectorNoiseModel* model) {
  const auto start = std::chrono::steady_clock::now();
  const BoxConventionOptions& box = options.calibration.box;
  FitOptions points_only = options.fit;
  points_only.detection_size_sigma = 0.0;
  points_only.detection_position = false;
  points_only.detection_length_bias = points_only.detection_height_bias = points_only.detection_width_bias = 0.0;
  points_only.detection_along_bias = 0.0;
  points_only.keep_points = false;
  const TrackFitter fitter(shape_model, points_only);
  const int num_sequences = int(options.sequences.size());
  std::vector<std::vector<BoxConventionSample>> samples_of_sequence(num_sequences);
  std::vector<int> fitted_of_sequence(num_sequences, 0);
  auto horizontal_distance = [](const ObjectLabel& d) { return std::hypot(d.position.x(), d.position.z()); };
  arena->execute([&] {
    tbb::parallel_for(0, num_sequences, [&](int s) {
      std::vector<Track> tracks;
      try {
        SequenceOptions seq_options = options.sequence;
        if (!options.tracking_labels.empty()) seq_options.tracking_labels_path = options.tracking_labels[s];
        SequenceSummary ignored;
        tracks = LoadSequenceTracks(options.sequences[s], seq_options, &ignored);
      } catch (const std::exception& e) {
        LogWarning() << "box convention: sequence " << options.sequences[s] << " left out: " << e.what();
        return;
      }
      std::vector<size_t> near;
      for (size_t t = 0; t < tracks.size(); ++t) {
        for (const TrackFrame& f : tracks[t].frames) {
          if (horizontal_distance(f.detection) <= box.max_distance &&
              int(f.candidate_points_in_world.size()) >= box.min_points) {
            near.push_back(t);
            break;
          }
        }
      }
      std::vector<std::vector<BoxConventionSample>> of_track(near.size());
      tbb::parallel_for(size_t(0), near.size(), [&](size_t i) {
        const Track& track = tracks[near[i]];
        TrackFit fit;
        try {
          fit = fitter.Fit(track);
        } catch (const std::exception&) {
          return;  // fails again in the fit, with its message
        }
        if (!fit.summary.UnusableReason().empty() || fit.frames.size() != track.frames.size()) return;
        for (size_t k = 0; k < track.frames.size(); ++k) {
          const TrackFrame& f = track.frames[k];
          const FrameFit& ff = fit.frames[k];
          const Eigen::VectorXd& z = fit.single_frame ? ff.shape_code : fit.shape_code;
          const AlignedBox inside = fitter.lookup().InsideBox(z);
          if (inside.IsEmpty()) continue;
          const Eigen::Vector3d extent = inside.Size();  // l h w (object x y z)
          BoxConventionSample sample;
          sample.car = s * 1000000 + track.id;
          sample.distance = horizontal_distance(f.detection);
          sample.num_points = ff.num_points;
          sample.detected[0] = f.detection.height, sample.detected[1] = f.detection.width;
          sample.detected[2] = f.detection.length;
          sample.fitted[0] = extent.y(), sample.fitted[1] = extent.z(), sample.fitted[2] = extent.x();
          const Eigen::Vector3d p = f.detection.position;
          const Eigen::Vector3d ray = Eigen::Vector3d(p.x(), 0.0, p.z()).normalized();
          const Eigen::Vector3d fitted_in_camera = f.world_from_camera.inverse() * ff.position;
          sample.along = (p - fitted_in_camera).dot(ray);
          const Eigen::Vector3d axis(std::cos(f.detection.rotation_y), 0.0, -std::sin(f.detection.rotation_y));
          sample.view_angle_deg = std::acos(std::min(1.0, std::abs(axis.dot(ray)))) * 180.0 / kPi;
          of_track[i].push_back(sample);
        }
      });
      for (const auto& samples : of_track) {
        fitted_of_sequence[s] += !samples.empty();
        samples_of_sequence[s].insert(samples_of_sequence[s].end(), samples.begin(), samples.end());
      }
    });
  });
  std::vector<BoxConventionSample> samples;
  int cars = 0;
  for (int s = 0; s < num_sequences; ++s) {
    samples.insert(samples.end(), samples_of_sequence[s].begin(), samples_of_sequence[s].end());
    cars += fitted_of_sequence[s];
  }
  const int used = EstimateBoxConvention(samples, box, model);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  LogInfo() << "box convention: " << cars << " near car(s) fitted to their points alone, " << used << " of "
            << samples.size() << " detections used, " << seconds << " s: "
            << (model->box_convention_estimated ? "estimated" : "not estimated") << " (box - shape h/w/l "
            << model->size_bias[0] << "/" << model->size_bias[1] << "/" << model->size_bias[2] << " m, along-ray "
            << model->along_bias << " m)";
}

}  // namespace

std::string SequenceOutputName(const std::string& directory) {
  try {
    const std::string name = ListSequence(directory).name;
    if (!name.empty()) return name;
  } catch (const std::exception&) {
    // Not a readable sequence: its folder's name (the sequence fails later).
  }
  fs::path path = fs::path(directory).lexically_normal();
  if (!path.has_filename() && path.has_parent_path()) path = path.parent_path();
  if (path.filename() == "." || path.filename() == "..") path = fs::absolute(path).lexically_normal();
  if (!path.has_filename() && path.has_parent_path()) path = path.parent_path();
  return path.filename().string();
}

RunFitSummary RunFit(const RunFitOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  options.Check();
  CheckSequenceNames(options);
  const bool earlier_run = CheckOutputFolder(options);
  RunFitSummary summary;
  // The options the sequences are linked and fitted with (the detector's
  // sigmas calibrated when asked); `options` is what config.json records.
  const auto calibration_start = std::chrono::steady_clock::now();
  RunFitOptions effective = CalibratedOptions(options, &summary);
  if (summary.detector_model_used && options.detector_model_path.empty())
    summary.seconds_calibration =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - calibration_start).count();
  tbb::task_arena arena(options.num_threads > 0 ? options.num_threads : tbb::task_arena::automatic);
  std::unique_ptr<ShapeModel> model;
  std::unique_ptr<TrackFitter> fitter;
  if (!options.link_only) {
    model = std::make_unique<ShapeModel>(ShapeModel::Load(options.model_path));
    // The box convention: given biases win; a model file's is applied; self-calibration measures it.
    const bool detection_terms = options.fit.detection_size_sigma > 0 || options.fit.detection_position;
    if (summary.detector_model_used && detection_terms && !HasGivenBoxBias(options.fit)) {
      if (options.detector_model_path.empty() && options.calibration.estimate_box_convention) {
        const auto box_start = std::chrono::steady_clock::now();
        EstimateRunBoxConvention(effective, *model, &arena, &summary.detector_model);
        summary.seconds_calibration +=
            std::chrono::duration<double>(std::chrono::steady_clock::now() - box_start).count();
        summary.calibration_report +=
            "; " + BoxConventionReport(summary.detector_model, options.calibration.box.apply_along_bias);
        for (const std::string& note : summary.detector_model.notes)
          if (note.rfind("box convention", 0) == 0) LogWarning() << "self-calibration: " << note;
      }
      ApplyBoxConvention(summary.detector_model, options.calibration.box.apply_along_bias, &effective.fit);
    }
    fitter = std::make_unique<TrackFitter>(*model, effective.fit);
  }
  // Every file goes into `staged`, which replaces output_dir at the end.
  StagedFolder staged(options.output_dir);
  const std::string& folder = staged.path();
  if (options.link_only) {
    LogInfo() << "linking " << options.sequences.size() << " sequence(s) into tracks (no fit)";
  } else {
    LogInfo() << "fitting " << options.sequences.size() << " sequence(s) with model " << options.model_path
              << " (" << model->NumComponents() << " components), "
              << (options.fit.single_frame ? "single-frame" : "joint SAMP") << " mode";
  }

  std::vector<SequenceWork> work(options.sequences.size());
  arena.execute([&] {
    tbb::parallel_for(size_t(0), work.size(), [&](size_t i) { FitSequence(effective, folder, fitter.get(), i, &work[i]); });
  });

  TracksFile tracks_file;
  tracks_file.model = options.model_path;
  tracks_file.detector_model = DetectorModelRecord(options, summary);
  for (SequenceWork& w : work) {
    summary.sequences.push_back(w.result);
    const SequenceFitResult& r = w.result;
    summary.num_sequences_failed += !r.ok;
    summary.num_tracks_fitted += r.num_fitted;
    summary.num_tracks_failed += int(r.track_failures.size());
    TracksFileSequence sequence;
    sequence.directory = r.directory;
    sequence.name = r.name;
    sequence.ok = r.ok;
    sequence.error = r.error;
    sequence.input = r.input.BriefReport();
    sequence.input_messages = r.input.messages;
    if (r.ok) sequence.tracking = nlohmann::json::parse(r.input.tracking.ToJson());
    sequence.tracks = std::move(w.tracks);
    sequence.failed_tracks = r.track_failures;
    tracks_file.sequences.push_back(std::move(sequence));
  }
  WriteTracksFile(FitTracksPath(folder), tracks_file);

  FitConfig config;
  config.options = options;
  config.model_components = model ? model->NumComponents() : 0;
  config.detector_model = tracks_file.detector_model;
  WriteFitConfig((fs::path(folder) / "config.json").string(), config);
  if (summary.detector_model_used) {
    WriteDetectorNoiseModel((fs::path(folder) / "detector_model.json").string(), summary.detector_model);
    if (options.detector_plot && options.draw_detector_model)
      options.draw_detector_model((fs::path(folder) / "detector_model.png").string(), summary.detector_model);
  }

  int num_detections = 0;
  for (const auto& q : summary.sequences) num_detections += q.input.tracking.num_detections;
  std::ostringstream failure;
  if (summary.num_sequences_failed == int(summary.sequences.size())) {
    failure << "every sequence failed";
  } else if (summary.num_sequences_failed > 0) {
    failure << summary.num_sequences_failed << " of " << summary.sequences.size() << " sequences failed:";
    for (const auto& q : summary.sequences)
      if (!q.ok) failure << " " << q.directory;
  } else if (!options.link_only && summary.num_tracks_fitted == 0 && num_detections > 0) {
    failure << "no track was fitted although the input had " << num_detections << " detection(s)";
    if (summary.num_tracks_failed > 0) failure << "; every track failed (" << summary.num_tracks_failed << ")";
    failure << " (see the messages above and tracks.json)";
  }
  summary.failure = failure.str();
  if (summary.failure.empty() && options.before_commit) options.before_commit(folder);
  if (!summary.failure.empty() && earlier_run) {
    // A failed run never replaces a good one: the earlier output stays.
    summary.kept_previous_output = true;
    LogWarning() << "the run failed (" << summary.failure << "): " << options.output_dir
                 << " keeps the output of the earlier run";
    summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return summary;
  }
  staged.Commit();
  summary.replaced_previous_output = earlier_run && staged.replaced();
  if (summary.replaced_previous_output) LogInfo() << "replaced " << options.output_dir << ", the output of an earlier run";
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace samp
