#include "libsamp/pipeline/run_fit.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>
#include <mutex>
#include <sstream>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/core/ply_io.h"
#include "libsamp/pipeline/fit_output.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/model/shape_model.h"

namespace samp {

namespace fs = std::filesystem;

bool RunFitOptions::Check() const {
  SAMP_CHECK(link_only || !model_path.empty()) << "RunFitOptions.model_path is empty";
  SAMP_CHECK(!sequences.empty()) << "RunFitOptions.sequences is empty (give at least one --seq)";
  SAMP_CHECK(tracking_labels.empty() || tracking_labels.size() == sequences.size())
      << "RunFitOptions.tracking_labels: " << tracking_labels.size() << " files for "
      << sequences.size() << " sequences (give none or one per sequence)";
  SAMP_CHECK(!output_dir.empty()) << "RunFitOptions.output_dir is empty";
  SAMP_CHECK(num_threads >= 1) << "RunFitOptions.num_threads must be >= 1";
  fit.Check();
  sequence.Check();
  return true;
}

std::string RunFitSummary::BriefReport() const {
  std::ostringstream s;
  s << sequences.size() << " sequence(s) (" << num_sequences_failed << " failed), "
    << num_tracks_fitted << " track(s) fitted, " << num_tracks_failed << " failed, " << seconds
    << " s";
  for (const auto& q : sequences) {
    s << "\n  " << (q.name.empty() ? q.directory : q.name) << ": ";
    if (!q.ok) {
      s << "FAILED: " << q.error;
      continue;
    }
    s << q.num_fitted << "/" << q.num_tracks << " tracks, " << q.seconds << " s; tracker: "
      << q.input.tracking.BriefReport();
    for (const auto& f : q.track_failures) s << "\n    skipped " << f;
  }
  return s.str();
}

namespace {

struct SequenceWork {
  SequenceFitResult result;
  std::vector<nlohmann::json> tracks_json;
};

std::string MeshPrefix(const RunFitOptions& options, const std::string& seq, int track_id) {
  const std::string dir = options.sequences.size() > 1 ? "meshes/" + seq + "/" : "meshes/";
  return dir + "track_" + std::to_string(track_id);
}

// fitter == nullptr: link only (the tracks' detections are the labels).
void FitSequence(const RunFitOptions& options, const TrackFitter* fitter, size_t index,
                 SequenceWork* work) {
  const auto start = std::chrono::steady_clock::now();
  SequenceFitResult& result = work->result;
  result.directory = options.sequences[index];
  std::vector<Track> tracks;
  try {
    SequenceOptions seq_options = options.sequence;
    if (!options.tracking_labels.empty()) seq_options.tracking_labels_path = options.tracking_labels[index];
    tracks = LoadSequenceTracks(result.directory, seq_options, &result.input);
    result.name = result.input.name;
    if (result.name.empty()) result.name = fs::path(result.directory).filename().string();
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
    std::stable_sort(labels.begin(), labels.end(), [](const ObjectLabel& a, const ObjectLabel& b) {
      return a.frame != b.frame ? a.frame < b.frame : a.track_id < b.track_id;
    });
    try {
      WriteTrackingLabels((fs::path(options.output_dir) / "label_02" / (result.name + ".txt")).string(), labels);
    } catch (const std::exception& e) {
      result.ok = false;
      result.error = std::string("writing labels: ") + e.what();
    }
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return;
  }
  std::vector<TrackFit> fits(tracks.size());
  std::vector<std::string> errors(tracks.size());
  tbb::parallel_for(size_t(0), tracks.size(), [&](size_t t) {
    try {
      fits[t] = fitter->Fit(tracks[t]);
      if (fits[t].sequence.empty()) fits[t].sequence = result.name;
    } catch (const std::exception& e) {
      errors[t] = e.what();
    }
  });
  std::vector<ObjectLabel> labels;
  for (size_t t = 0; t < tracks.size(); ++t) {
    if (!errors[t].empty()) {
      result.track_failures.push_back("track " + std::to_string(tracks[t].id) + ": " + errors[t]);
      LogWarning() << result.name << ": track " << tracks[t].id << " skipped: " << errors[t];
      continue;
    }
    try {
      const TrackFit& fit = fits[t];
      const std::vector<ObjectLabel> track_labels = FitToLabels(fit, tracks[t], fitter->lookup());
      nlohmann::json j = TrackFitToJson(fit, FittedBox(fitter->lookup(), fit.shape_code));
      if (options.write_meshes) {
        const std::string prefix = MeshPrefix(options, result.name, fit.track_id);
        const Mesh mesh = FittedSurface(fitter->lookup(), fit.shape_code);
        WritePly((fs::path(options.output_dir) / (prefix + ".ply")).string(), mesh);
        WritePly((fs::path(options.output_dir) / (prefix + "_points.ply")).string(),
                 AlignedObservations(fit));
        j["mesh"] = prefix + ".ply";
        j["points"] = prefix + "_points.ply";
      }
      labels.insert(labels.end(), track_labels.begin(), track_labels.end());
      work->tracks_json.push_back(std::move(j));
      ++result.num_fitted;
      LogInfo() << result.name << ": track " << fit.track_id << " (" << fit.frames.size()
                << " frames): " << fit.summary.BriefReport();
    } catch (const std::exception& e) {
      result.track_failures.push_back("track " + std::to_string(tracks[t].id) + ": " + e.what());
      LogWarning() << result.name << ": track " << tracks[t].id << " output failed: " << e.what();
    }
  }
  std::stable_sort(labels.begin(), labels.end(), [](const ObjectLabel& a, const ObjectLabel& b) {
    return a.frame != b.frame ? a.frame < b.frame : a.track_id < b.track_id;
  });
  try {
    WriteTrackingLabels((fs::path(options.output_dir) / "label_02" / (result.name + ".txt")).string(), labels);
  } catch (const std::exception& e) {
    result.ok = false;
    result.error = std::string("writing labels: ") + e.what();
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

RunFitSummary RunFit(const RunFitOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  options.Check();
  std::unique_ptr<ShapeModel> model;
  std::unique_ptr<TrackFitter> fitter;
  if (!options.link_only) {
    model = std::make_unique<ShapeModel>(ShapeModel::Load(options.model_path));
    fitter = std::make_unique<TrackFitter>(*model, options.fit);
  }
  fs::create_directories(options.output_dir);
  if (options.link_only) {
    LogInfo() << "linking " << options.sequences.size() << " sequence(s) into tracks (no fit)";
  } else {
    LogInfo() << "fitting " << options.sequences.size() << " sequence(s) with model " << options.model_path
              << " (" << model->NumComponents() << " components), "
              << (options.fit.single_frame ? "single-frame" : "joint SAMP") << " mode";
  }

  std::vector<SequenceWork> work(options.sequences.size());
  tbb::task_arena arena(options.num_threads);
  arena.execute([&] {
    tbb::parallel_for(size_t(0), work.size(), [&](size_t i) { FitSequence(options, fitter.get(), i, &work[i]); });
  });

  RunFitSummary summary;
  nlohmann::json tracks_json;
  tracks_json["model"] = options.model_path;
  tracks_json["sequences"] = nlohmann::json::array();
  for (SequenceWork& w : work) {
    summary.sequences.push_back(w.result);
    const SequenceFitResult& r = w.result;
    summary.num_sequences_failed += !r.ok;
    summary.num_tracks_fitted += r.num_fitted;
    summary.num_tracks_failed += int(r.track_failures.size());
    nlohmann::json js;
    js["directory"] = r.directory;
    js["name"] = r.name;
    js["ok"] = r.ok;
    if (!r.ok) js["error"] = r.error;
    js["input"] = r.input.BriefReport();
    js["input_messages"] = r.input.messages;
    if (r.ok) js["tracking"] = nlohmann::json::parse(r.input.tracking.ToJson());
    js["tracks"] = w.tracks_json;
    js["failed_tracks"] = r.track_failures;
    tracks_json["sequences"].push_back(js);
  }
  WriteTextFileAtomically((fs::path(options.output_dir) / "tracks.json").string(), tracks_json.dump(2) + "\n");

  nlohmann::json config;
  config["model"] = options.model_path;
  config["model_components"] = model ? model->NumComponents() : 0;
  config["link_only"] = options.link_only;
  config["sequences"] = options.sequences;
  config["tracking_labels"] = options.tracking_labels;
  config["fit"] = FitOptionsToJson(options.fit);
  const SequenceOptions& so = options.sequence;
  config["sequence"] = {
      {"object_types", so.object_types},
      {"min_detection_score", so.min_detection_score},
      {"first_frame", so.first_frame},
      {"last_frame", so.last_frame},
      {"observations",
       {{"box_margin", so.observations.box_margin},
        {"min_height_above_road", so.observations.min_height_above_road},
        {"max_distance_to_detection", so.observations.max_distance_to_detection},
        {"depth_gate_sigmas", so.observations.depth_gate_sigmas},
        {"min_disparity_px", so.observations.min_disparity_px},
        {"sigma_disparity_px", so.observations.sigma_disparity_px},
        {"max_points_per_frame", so.observations.max_points_per_frame},
        {"seed", so.observations.seed}}},
      {"tracker", nlohmann::json::parse(so.tracker.ToJson())}};
  config["num_threads"] = options.num_threads;
  config["write_meshes"] = options.write_meshes;
  WriteTextFileAtomically((fs::path(options.output_dir) / "config.json").string(), config.dump(2) + "\n");
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace samp
