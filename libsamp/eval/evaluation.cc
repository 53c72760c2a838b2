#include "libsamp/eval/evaluation.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <set>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/core/json_text.h"
#include "libsamp/core/log.h"
#include "libsamp/core/progress.h"
#include "libsamp/core/util.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/sequence.h"
#include "libsamp/data/stereo.h"
#include "libsamp/eval/eval_option_table.h"
#include "libsamp/eval/eval_inputs.h"
#include "libsamp/eval/eval_report.h"
#include "libsamp/eval/matching.h"
#include "libsamp/eval/metrics.h"
#include "libsamp/scan/renderer.h"

namespace samp {
namespace {

namespace fs = std::filesystem;
using eval::kDetections;
using eval::kStereo;

std::vector<Eigen::Vector3d> BackProjectDepth(const cv::Mat& depth_mm256,
                                              const std::vector<cv::Point>& pixels,
                                              const PinholeCamera& camera) {
  std::vector<Eigen::Vector3d> points;
  points.reserve(pixels.size());
  for (const cv::Point& p : pixels) {
    const uint16_t value = depth_mm256.at<uint16_t>(p);
    if (value == 0) continue;
    points.push_back(camera.Ray(p.x, p.y) * (value / 256.0));
  }
  return points;
}

// Renders `mesh` at `camera_from_object` into the part of the camera covering
// `pixels` and returns the surface points seen at those pixels.
std::vector<Eigen::Vector3d> RenderedPoints(const Mesh& mesh, const Eigen::Isometry3d& camera_from_object,
                                            const std::vector<cv::Point>& pixels,
                                            const PinholeCamera& camera) {
  if (pixels.empty()) return {};
  int u0 = camera.width, v0 = camera.height, u1 = -1, v1 = -1;
  for (const cv::Point& p : pixels) {
    u0 = std::min(u0, p.x), v0 = std::min(v0, p.y), u1 = std::max(u1, p.x), v1 = std::max(v1, p.y);
  }
  PinholeCamera crop = camera;
  crop.width = u1 - u0 + 1;
  crop.height = v1 - v0 + 1;
  crop.cx = camera.cx - u0;
  crop.cy = camera.cy - v0;
  const RenderBuffers buffers = Render(crop, {PlacedMesh{&mesh, camera_from_object}});
  std::vector<Eigen::Vector3d> points;
  points.reserve(pixels.size());
  for (const cv::Point& p : pixels) {
    const float z = buffers.Depth(p.x - u0, p.y - v0);
    if (!std::isfinite(z)) continue;
    points.push_back(camera.Ray(p.x, p.y) * double(z));
  }
  return points;
}

// The score stage: one true car-frame with its segment's pixels and, per
// matching and method, the matched label.
struct CarFrameWork {
  CarFrameRecord record;
  std::vector<cv::Point> pixels;
  std::vector<const ObjectLabel*> matched[kNumMatchings];  // per method
};

// The pose errors of estimate `e` of true car `truth`.
void ScorePose(const ObjectLabel& truth, const ObjectLabel& e, MethodCarFrame* r) {
  r->matched = true;
  r->output_track = e.track_id;
  r->translation_error = (e.position - truth.position).norm();
  r->yaw_error_deg = YawErrorDeg(e.rotation_y, truth.rotation_y);
  Eigen::Vector3d ray(truth.position.x(), 0.0, truth.position.z());
  ray = ray.norm() > 1e-9 ? Eigen::Vector3d(ray.normalized()) : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d error = e.position - truth.position;
  r->along_ray_offset = error.dot(ray);
  r->lateral_offset = error.dot(Eigen::Vector3d(ray.z(), 0.0, -ray.x()));
  r->vertical_offset = error.y();
  r->size = Eigen::Vector3d(e.height, e.width, e.length);
}

// The car-frame of truth t of `frame` with the methods' matches and pose
// errors; the matched results' surfaces are loaded into *result_meshes.
CarFrameWork MakeCarFrame(const eval::SequenceInputs& inputs, const eval::SequenceMatches& matches,
                          const std::vector<EvalMethod>& methods, int frame, size_t t,
                          std::vector<std::unique_ptr<eval::ResultMeshes>>* result_meshes) {
  const ObjectLabel& truth = inputs.gt_by_frame.at(frame)[t];
  CarFrameWork w;
  w.record.sequence = inputs.seq;
  w.record.track_id = truth.track_id;
  w.record.frame = frame;
  w.record.distance = truth.position.norm();
  if (inputs.has_maps) w.pixels = inputs.segments.at(frame)[t];
  w.record.segment_pixels = int(w.pixels.size());
  w.record.true_size = Eigen::Vector3d(truth.height, truth.width, truth.length);
  for (int k = 0; k < kNumMatchings; ++k) {
    w.record.methods[k].resize(methods.size());
    w.matched[k].assign(methods.size(), nullptr);
  }
  for (size_t m = 0; m < methods.size(); ++m) {
    if (methods[m].name == kStereo) {
      for (int k = 0; k < kNumMatchings; ++k) w.record.methods[k][m].matched = true;
      continue;
    }
    for (int k = 0; k < kNumMatchings; ++k) {
      const int index = matches.Match(inputs, k, m, frame, t);
      if (index < 0) continue;
      const ObjectLabel& e = eval::LabelsAt(inputs, m, frame)[index];
      w.matched[k][m] = &e;
      ScorePose(truth, e, &w.record.methods[k][m]);
      if (methods[m].shape) (*result_meshes)[m]->Load(inputs.seq, e.track_id, frame);
    }
  }
  return w;
}

// The evaluated car-frames (SequenceInputs::evaluated); the true
// cars' names "<seq>/<id>" go to *tracks.
std::vector<CarFrameWork> CarFrames(const eval::SequenceInputs& inputs,
                                    const eval::SequenceMatches& matches, const std::vector<EvalMethod>& methods,
                                    std::vector<std::unique_ptr<eval::ResultMeshes>>* result_meshes,
                                    std::set<std::string>* tracks) {
  std::vector<CarFrameWork> work;
  for (const auto& [frame, truths] : inputs.gt_by_frame) {
    for (size_t t = 0; t < truths.size(); ++t) {
      if (!inputs.evaluated.at(frame)[t]) continue;
      work.push_back(MakeCarFrame(inputs, matches, methods, frame, t, result_meshes));
      tracks->insert(inputs.seq + "/" + std::to_string(truths[t].track_id));
    }
  }
  return work;
}

// The estimated points of method m for car-frame w under matching k: the input
// disparity inside the segment (stereo) or the matched result's surface
// rendered at its label's pose.
std::vector<Eigen::Vector3d> EstimatedPoints(const eval::SequenceInputs& inputs, const EvalMethod& method,
                                             const eval::ResultMeshes* meshes, const cv::Mat* disparity,
                                             const CarFrameWork& w, int k, size_t m) {
  std::vector<Eigen::Vector3d> estimated;
  if (method.name == kStereo) {
    for (const cv::Point& p : w.pixels) {
      const float d = disparity->at<float>(p);
      if (d > 0.f) estimated.push_back(DisparityToPoint(p.x, p.y, d, inputs.calibration));
    }
    return estimated;
  }
  const ObjectLabel& e = *w.matched[k][m];
  const Mesh& mesh = meshes->Get(inputs.seq, e.track_id, w.record.frame);
  return RenderedPoints(mesh, eval::CameraFromObject(e), w.pixels, inputs.calibration.camera);
}

// The shape scores of every shape method on car-frame w against its true points.
void ScoreShapes(const EvalOptions& options, const eval::SequenceInputs& inputs,
                 const std::vector<EvalMethod>& methods,
                 const std::vector<std::unique_ptr<eval::ResultMeshes>>& result_meshes, const cv::Mat& depth,
                 const cv::Mat* disparity, CarFrameWork* w) {
  const std::vector<Eigen::Vector3d> truth = BackProjectDepth(depth, w->pixels, inputs.calibration.camera);
  w->record.num_true_points = int(truth.size());
  for (size_t m = 0; m < methods.size(); ++m) {
    for (int k = 0; k < kNumMatchings; ++k) {
      MethodCarFrame& r = w->record.methods[k][m];
      if (!methods[m].shape || !r.matched) continue;
      const MethodCarFrame& per_track = w->record.methods[kPerTrack][m];
      if (k == kPerFrame && w->matched[kPerTrack][m] == w->matched[kPerFrame][m] && per_track.has_shape) {
        r.num_estimated_points = per_track.num_estimated_points;  // the same box: the same scores
        r.scores = per_track.scores;
        r.has_shape = true;
        continue;
      }
      const std::vector<Eigen::Vector3d> estimated =
          EstimatedPoints(inputs, methods[m], result_meshes[m].get(), disparity, *w, k, m);
      r.num_estimated_points = int(estimated.size());
      const ShapeComparison comparison = CompareShapes(estimated, truth, options.taus.back());
      for (double tau : options.taus) r.scores.push_back(comparison.At(tau));
      r.has_shape = true;
    }
  }
}

// The score stage: the depth maps (and disparities for the stereo baseline) of
// the car-frames' frames are read first, then the car-frames are scored in parallel.
void ScoreCarFrames(const EvalOptions& options, const eval::SequenceInputs& inputs,
                    const std::vector<EvalMethod>& methods,
                    const std::vector<std::unique_ptr<eval::ResultMeshes>>& result_meshes,
                    std::vector<CarFrameWork>* work) {
  if (!inputs.has_maps) return;  // pose and tracking only
  std::map<int, cv::Mat> depths, disparities;
  for (const CarFrameWork& w : *work) {
    const int f = w.record.frame;
    if (depths.count(f)) continue;
    depths[f] = eval::ReadPngOfType(inputs.layout.GroundTruthDepth(f), CV_16UC1, inputs.size);
    if (!options.stereo_baseline) continue;
    const fs::path disparity = inputs.layout.Disparity(f);
    SAMP_CHECK(fs::exists(disparity)) << "eval: missing " << disparity.string() << " (needed by the stereo baseline)";
    disparities[f] = ReadDisparity(disparity.string(), inputs.size);
  }
  for (const auto& meshes : result_meshes) {
    if (meshes) meshes->Finish();
  }
  tbb::parallel_for(size_t(0), work->size(), [&](size_t i) {
    CarFrameWork& w = (*work)[i];
    const auto disparity = disparities.find(w.record.frame);
    ScoreShapes(options, inputs, methods, result_meshes, depths.at(w.record.frame),
                disparity == disparities.end() ? nullptr : &disparity->second, &w);
  });
}

// One sequence through the three stages: load (ground truth, labels), match
// (per track and per frame, tracking counts), score (pose and shape).
std::vector<CarFrameRecord> EvaluateSequence(const EvalOptions& options, const std::string& directory,
                                             const std::vector<EvalMethod>& methods,
                                             std::vector<std::unique_ptr<eval::ResultMeshes>>* result_meshes,
                                             std::set<std::string>* tracks, std::vector<TrackingCounts>* tracking) {
  eval::SequenceInputs inputs;
  if (!eval::LoadSequenceInputs(options, directory, methods, &inputs)) return {};
  const eval::SequenceMatches matches = eval::MatchSequence(options, inputs, methods, tracking);
  std::vector<CarFrameWork> work = CarFrames(inputs, matches, methods, result_meshes, tracks);
  ScoreCarFrames(options, inputs, methods, *result_meshes, &work);
  std::vector<CarFrameRecord> records;
  for (CarFrameWork& w : work) records.push_back(std::move(w.record));
  return records;
}

PoseWindow MakeWindow(double lo, double hi, const std::vector<double>& translation,
                      const std::vector<double>& yaw) {
  PoseWindow w;
  w.min_distance = lo;
  w.max_distance = hi;
  w.count = int(translation.size());
  w.translation_mean = Mean(translation);
  w.translation_median = Median(translation);
  w.yaw_mean_deg = Mean(yaw);
  w.yaw_median_deg = Median(yaw);
  return w;
}

}  // namespace

void EvalOptions::Check() const {
  SAMP_CHECK(!sequences.empty()) << "eval: no sequence given";
  SAMP_CHECK(!output_folder.empty()) << "eval: output_folder is empty";
  std::set<std::string> names;
  for (const auto& [name, folder] : results) {
    SAMP_CHECK(!name.empty() && name.find_first_of(" ,\t\n") == std::string::npos)
        << "eval: result name '" << name << "' must be non-empty without spaces or commas";
    SAMP_CHECK(name != kStereo && name != kDetections)
        << "eval: result name '" << name << "' is reserved for a baseline";
    SAMP_CHECK(names.insert(name).second) << "eval: result name '" << name << "' given twice";
    SAMP_CHECK(fs::is_directory(folder)) << "eval: result folder " << folder << " (" << name
                                         << ") does not exist";
  }
  SAMP_CHECK(!results.empty() || stereo_baseline || detection_baseline)
      << "eval: nothing to evaluate (no result and no baseline)";
  SAMP_CHECK(!taus.empty()) << "eval: taus is empty";
  for (size_t i = 0; i < taus.size(); ++i) {
    SAMP_CHECK(taus[i] > 0 && std::isfinite(taus[i])) << "eval: taus must be > 0";
    SAMP_CHECK(i == 0 || taus[i] > taus[i - 1]) << "eval: taus must be increasing";
  }
  EvalOptionTable().Check(*this);
}

std::string EvalOptions::ToJson() const {
  return DumpJson(OptionsToJson(*this), 2);
}

size_t EvalSummary::HeadlineIndex() const {
  size_t headline = 0;
  for (size_t i = 0; i < taus.size(); ++i) {
    if (std::abs(taus[i] - headline_tau) < 1e-9) headline = i;
  }
  return headline;
}

std::string EvalSummary::BriefReport() const {
  std::ostringstream out;
  out << "eval: " << num_sequences << " sequences, " << num_gt_tracks << " tracks, "
      << num_gt_car_frames << " car-frames";
  const size_t headline = HeadlineIndex();
  for (const MethodShapeResult& s : shape) {
    if (s.f1.empty()) continue;
    out << "; " << s.method << " F1@" << Fixed(headline_tau, 2) << " " << Fixed(100.0 * s.f1[headline], 2) << "%";
  }
  for (const MethodShapeResult& s : shape_per_frame) {
    if (s.f1.empty() || s.method == "stereo") continue;
    out << "; " << s.method << " per frame " << Fixed(100.0 * s.f1[headline], 2) << "%";
  }
  for (const MethodPoseResult& p : pose) {
    out << "; " << p.method << " median " << Fixed(p.all.translation_median, 2) << " m / "
        << Fixed(p.all.yaw_median_deg, 1) << " deg";
  }
  for (const MethodTrackingResult& t : tracking) {
    out << "; " << t.method << " " << Fixed(t.counts.TracksPerCar(), 2) << " tracks/car, IDSW "
        << t.counts.id_switches << ", MOTA " << Fixed(100 * t.counts.Mota(), 1) << "%";
  }
  out << " (" << Fixed(seconds, 1) << " s)";
  return out.str();
}

namespace {

// The baselines, then the results. A result without meshes (e.g. `samp fit
// --link-only`, another tracker's labels) is evaluated for pose and tracking
// only. A result folder without labels of any given sequence (a wrong path, a
// fit that wrote nothing) would score 0 % without a word: an error.
// Sequences of KITTI tracking's layout have no ground-truth maps: no shape
// figures, no stereo baseline, and the detection baseline only with
// EvalOptions::detections_path.
std::vector<EvalMethod> MakeMethods(const EvalOptions& options) {
  size_t num_kitti = 0;
  for (const std::string& sequence : options.sequences) num_kitti += eval::IsKittiTrackingSequence(sequence) ? 1 : 0;
  SAMP_CHECK(num_kitti == 0 || num_kitti == options.sequences.size())
      << "eval: " << num_kitti << " of the " << options.sequences.size()
      << " sequences are of KITTI tracking's layout (pose and tracking only): evaluate them apart from "
         "sequences with ground-truth maps";
  const bool maps = num_kitti == 0;
  if (!maps && options.stereo_baseline) {
    LogInfo() << "eval: KITTI tracking's layout has no depth maps: pose and tracking figures only, no stereo baseline";
  }
  if (!maps && options.detection_baseline && options.detections_path.empty()) {
    LogWarning() << "eval: no detection baseline for KITTI tracking's layout without --detections";
  }
  std::vector<EvalMethod> methods;
  if (options.stereo_baseline && maps) methods.push_back({kStereo, "", true, false});
  if (options.detection_baseline && (maps || !options.detections_path.empty())) {
    methods.push_back({kDetections, "", false, true});
  }
  auto has_meshes = [](const std::string& folder) {
    if (fs::is_directory(fs::path(folder) / "meshes")) return true;
    for (const auto& entry : fs::directory_iterator(folder))
      if (entry.is_directory() && fs::is_directory(entry.path() / "meshes")) return true;
    return false;
  };
  std::vector<std::string> names;
  for (const std::string& sequence : options.sequences) names.push_back(ListSequence(sequence).name);
  for (const auto& [name, folder] : options.results) {
    // A lambda may not capture a structured binding in C++17 (clang refuses it).
    const std::string& result_folder = folder;
    const bool any = std::any_of(names.begin(), names.end(), [&](const std::string& seq) {
      return !eval::ResultFolder(result_folder, seq).empty();
    });
    SAMP_CHECK(any) << "eval: result folder " << folder << " (" << name << ") has no results for any of the "
                    << names.size() << " sequence(s): no label_02/<seq>.txt or <seq>/label_02/<seq>.txt for "
                    << names.front() << (names.size() > 1 ? ", ..." : "");
  }
  for (const auto& [name, folder] : options.results) {
    methods.push_back({name, folder, maps && has_meshes(folder), true});
  }
  SAMP_CHECK(!methods.empty()) << "eval: nothing to evaluate (no result and no baseline)";
  return methods;
}

// Every sequence in turn, with --threads workers (0 = all cores) in a task
// arena of this call, as samp fit and samp train do: no process-wide limit.
void EvaluateSequences(const EvalOptions& options, const std::vector<EvalMethod>& methods,
                       std::vector<CarFrameRecord>* records, std::set<std::string>* tracks,
                       std::vector<TrackingCounts>* tracking) {
  Progress progress("eval sequences", int64_t(options.sequences.size()));
  tbb::task_arena arena(options.num_threads > 0 ? options.num_threads : tbb::task_arena::automatic);
  arena.execute([&] {
    for (const std::string& sequence : options.sequences) {
      std::vector<std::unique_ptr<eval::ResultMeshes>> result_meshes(methods.size());
      for (size_t m = 0; m < methods.size(); ++m) {
        if (!methods[m].shape || methods[m].folder.empty()) continue;
        const std::string folder = eval::ResultFolder(methods[m].folder, ListSequence(sequence).name);
        if (!folder.empty()) result_meshes[m] = std::make_unique<eval::ResultMeshes>(folder);
      }
      std::vector<CarFrameRecord> r = EvaluateSequence(options, sequence, methods, &result_meshes, tracks, tracking);
      records->insert(records->end(), std::make_move_iterator(r.begin()), std::make_move_iterator(r.end()));
      progress.Tick();
    }
  });
  progress.Finish();
}

// Whether every shape (or pose) method matched car-frame r under matching k.
bool InCommonSet(const std::vector<EvalMethod>& methods, const CarFrameRecord& r, int k, bool shape) {
  for (size_t m = 0; m < methods.size(); ++m) {
    if ((shape ? methods[m].shape : methods[m].pose) && !r.methods[k][m].matched) return false;
  }
  return true;
}

// Shape scores of method m under matching k, means over the common set.
MethodShapeResult AggregateShape(const EvalOptions& options, const EvalResults& results, int k, size_t m) {
  MethodShapeResult s;
  s.method = results.methods[m].name;
  s.accuracy.assign(options.taus.size(), 0.0);
  s.completeness.assign(options.taus.size(), 0.0);
  s.f1.assign(options.taus.size(), 0.0);
  for (const CarFrameRecord& r : results.records) {
    if (r.methods[k][m].matched) ++s.num_matched;
    if (!InCommonSet(results.methods, r, k, true)) continue;
    ++s.num_evaluated;
    for (size_t i = 0; i < options.taus.size(); ++i) {
      s.accuracy[i] += r.methods[k][m].scores[i].accuracy;
      s.completeness[i] += r.methods[k][m].scores[i].completeness;
      s.f1[i] += r.methods[k][m].scores[i].f1;
    }
  }
  for (size_t i = 0; i < options.taus.size(); ++i) {
    const double n = std::max(1, s.num_evaluated);
    s.accuracy[i] /= n, s.completeness[i] /= n, s.f1[i] /= n;
  }
  return s;
}

// The distance window of a car-frame (the last one takes everything beyond).
int WindowOf(const EvalOptions& options, const CarFrameRecord& r, int num_windows) {
  return std::min(num_windows - 1, int(r.distance / options.distance_window));
}

// Pose errors of method m under matching k over the common set, in distance windows.
MethodPoseResult AggregatePose(const EvalOptions& options, const EvalResults& results, int k, size_t m) {
  const int num_windows = results.num_windows;
  MethodPoseResult p;
  p.method = results.methods[m].name;
  std::vector<std::vector<double>> translation(num_windows), yaw(num_windows);
  std::vector<double> all_translation, all_yaw, far_translation, far_yaw;
  for (const CarFrameRecord& r : results.records) {
    const MethodCarFrame& mr = r.methods[k][m];
    if (mr.matched) ++p.num_matched;
    if (!InCommonSet(results.methods, r, k, false)) continue;
    const int w = WindowOf(options, r, num_windows);
    translation[w].push_back(mr.translation_error);
    yaw[w].push_back(mr.yaw_error_deg);
    all_translation.push_back(mr.translation_error);
    all_yaw.push_back(mr.yaw_error_deg);
    if (w > 0) {
      far_translation.push_back(mr.translation_error);
      far_yaw.push_back(mr.yaw_error_deg);
    }
  }
  const double window = options.distance_window;
  for (int w = 0; w < num_windows; ++w) {
    p.windows.push_back(MakeWindow(w * window, (w + 1) * window, translation[w], yaw[w]));
  }
  p.all = MakeWindow(0.0, num_windows * window, all_translation, all_yaw);
  p.beyond_first = MakeWindow(window, num_windows * window, far_translation, far_yaw);
  return p;
}

// Per-car diagnostics of method m in distance window w (w = num_windows: all
// distances), per-frame matching: every matched car-frame of the method.
DiagnosticsBand Diagnostics(const EvalOptions& options, const EvalResults& results, size_t m, int w,
                            size_t headline) {
  const int num_windows = results.num_windows;
  DiagnosticsBand band;
  band.method = results.methods[m].name;
  band.min_distance = w < num_windows ? w * options.distance_window : 0.0;
  band.max_distance = w < num_windows ? (w + 1) * options.distance_window : num_windows * options.distance_window;
  std::vector<double> along, lateral, vertical, dh, dw, dl, f1;
  for (const CarFrameRecord& r : results.records) {
    const MethodCarFrame& mr = r.methods[kPerFrame][m];
    if (!mr.matched) continue;
    if (w < num_windows && WindowOf(options, r, num_windows) != w) continue;
    along.push_back(mr.along_ray_offset);
    lateral.push_back(std::abs(mr.lateral_offset));
    vertical.push_back(std::abs(mr.vertical_offset));
    dh.push_back(mr.size[0] - r.true_size[0]);
    dw.push_back(mr.size[1] - r.true_size[1]);
    dl.push_back(mr.size[2] - r.true_size[2]);
    if (mr.has_shape) f1.push_back(mr.scores[headline].f1);
  }
  band.count = int(along.size());
  band.along_ray_offset = Median(along);
  band.abs_lateral_offset = Median(lateral);
  band.abs_vertical_offset = Median(vertical);
  band.size_error = Eigen::Vector3d(Median(dh), Median(dw), Median(dl));
  band.f1 = Median(f1);
  band.num_shape = int(f1.size());
  return band;
}

}  // namespace

EvalResults ComputeEvaluation(const EvalOptions& options) {
  options.Check();
  EvalResults results;
  results.methods = MakeMethods(options);
  results.without_maps = eval::IsKittiTrackingSequence(options.sequences.front());
  const std::vector<EvalMethod>& methods = results.methods;
  std::set<std::string> tracks;
  std::vector<TrackingCounts> tracking(methods.size());
  EvaluateSequences(options, methods, &results.records, &tracks, &tracking);

  EvalSummary& summary = results.summary;
  summary.taus = options.taus;
  summary.headline_tau = options.headline_tau;
  summary.num_sequences = int(options.sequences.size());
  summary.num_gt_car_frames = int(results.records.size());
  summary.num_gt_tracks = int(tracks.size());
  double max_distance = 0.0;
  for (const CarFrameRecord& r : results.records) max_distance = std::max(max_distance, r.distance);
  results.num_windows = std::max(1, int(std::ceil(max_distance / options.distance_window)));
  for (int k = 0; k < kNumMatchings; ++k) {
    std::vector<MethodShapeResult>& shape = k == kPerTrack ? summary.shape : summary.shape_per_frame;
    std::vector<MethodPoseResult>& pose = k == kPerTrack ? summary.pose : summary.pose_per_frame;
    for (size_t m = 0; m < methods.size(); ++m) {
      if (methods[m].shape) shape.push_back(AggregateShape(options, results, k, m));
    }
    for (size_t m = 0; m < methods.size(); ++m) {
      if (methods[m].pose) pose.push_back(AggregatePose(options, results, k, m));
    }
  }
  // Tracking figures of the results (not of the baselines).
  for (size_t m = 0; m < methods.size(); ++m) {
    if (methods[m].name == kStereo || methods[m].name == kDetections) continue;
    summary.tracking.push_back({methods[m].name, tracking[m]});
  }
  for (size_t m = 0; m < methods.size(); ++m) {
    if (!methods[m].pose) continue;
    for (int w = 0; w <= results.num_windows; ++w) {
      summary.diagnostics.push_back(Diagnostics(options, results, m, w, summary.HeadlineIndex()));
    }
  }
  return results;
}

EvalSummary Evaluate(const EvalOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  EvalResults results = ComputeEvaluation(options);
  results.summary.markdown = EvalMarkdown(options, results);
  WriteEvalReport(options, results);
  results.summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return results.summary;
}

}  // namespace samp
