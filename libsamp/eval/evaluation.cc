#include "libsamp/eval/evaluation.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/core/json_text.h"
#include "libsamp/core/log.h"
#include "libsamp/core/progress.h"
#include "libsamp/core/util.h"
#include "libsamp/eval/eval_report.h"
#include "libsamp/eval/metrics.h"
#include "libsamp/pipeline/fit_output.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/sequence.h"
#include "libsamp/data/sequence_layout.h"
#include "libsamp/model/shape_lookup.h"
#include "libsamp/model/shape_model.h"
#include "libsamp/data/stereo.h"
#include "libsamp/data/tracking.h"
#include "libsamp/scan/mesh_io.h"
#include "libsamp/scan/renderer.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

constexpr char kStereo[] = "stereo";
constexpr char kDetections[] = "detections";

Eigen::Isometry3d CameraFromObject(const ObjectLabel& label) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  const double c = std::cos(label.rotation_y), s = std::sin(label.rotation_y);
  t.linear() << c, 0, s, 0, 1, 0, -s, 0, c;
  t.translation() = label.position;
  return t;
}

// The 2D box (x1, y1, x2, y2) of the projected 3D box, clipped to the image;
// all zero when nothing of it lies in front of the camera.
Eigen::Vector4d ProjectedBox(const ObjectLabel& label, const PinholeCamera& camera) {
  const Eigen::Isometry3d camera_from_object = CameraFromObject(label);
  double x1 = 1e300, y1 = 1e300, x2 = -1e300, y2 = -1e300;
  bool any = false;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d corner((i & 1 ? 0.5 : -0.5) * label.length, (i & 2 ? -label.height : 0.0),
                                 (i & 4 ? 0.5 : -0.5) * label.width);
    const Eigen::Vector3d p = camera_from_object * corner;
    if (p.z() < 0.1) continue;
    const Eigen::Vector2d uv = camera.Project(p);
    x1 = std::min(x1, uv.x()), y1 = std::min(y1, uv.y());
    x2 = std::max(x2, uv.x()), y2 = std::max(y2, uv.y());
    any = true;
  }
  if (!any) return Eigen::Vector4d::Zero();
  x1 = std::clamp(x1, 0.0, camera.width - 1.0), x2 = std::clamp(x2, 0.0, camera.width - 1.0);
  y1 = std::clamp(y1, 0.0, camera.height - 1.0), y2 = std::clamp(y2, 0.0, camera.height - 1.0);
  return Eigen::Vector4d(x1, y1, x2, y2);
}

double BoxIou(const Eigen::Vector4d& a, const Eigen::Vector4d& b) {
  const double iw = std::min(a[2], b[2]) - std::max(a[0], b[0]);
  const double ih = std::min(a[3], b[3]) - std::max(a[1], b[1]);
  if (iw <= 0 || ih <= 0) return 0.0;
  const double inter = iw * ih;
  const double area_a = (a[2] - a[0]) * (a[3] - a[1]), area_b = (b[2] - b[0]) * (b[3] - b[1]);
  return inter / std::max(1e-12, area_a + area_b - inter);
}

// Greedy one-to-one matching by decreasing IoU. Returns per truth the index of
// the matched estimate or -1.
std::vector<int> MatchBoxes(const std::vector<Eigen::Vector4d>& truth,
                            const std::vector<Eigen::Vector4d>& estimates, double min_iou) {
  struct Pair {
    double iou;
    int t, e;
  };
  std::vector<Pair> pairs;
  for (size_t t = 0; t < truth.size(); ++t) {
    for (size_t e = 0; e < estimates.size(); ++e) {
      const double iou = BoxIou(truth[t], estimates[e]);
      if (iou >= min_iou) pairs.push_back({iou, int(t), int(e)});
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
    if (a.iou != b.iou) return a.iou > b.iou;
    if (a.t != b.t) return a.t < b.t;
    return a.e < b.e;
  });
  std::vector<int> match(truth.size(), -1);
  std::vector<bool> used(estimates.size(), false);
  for (const Pair& p : pairs) {
    if (match[p.t] >= 0 || used[p.e]) continue;
    match[p.t] = p.e;
    used[p.e] = true;
  }
  return match;
}

cv::Mat ReadPngOfType(const std::string& path, int type, const cv::Size& size) {
  SAMP_CHECK(fs::exists(path)) << "eval: missing file " << path;
  cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  SAMP_CHECK(!image.empty()) << "eval: cannot decode " << path;
  SAMP_CHECK(image.type() == type) << "eval: " << path << " has the wrong pixel type (expected "
                                   << (type == CV_16UC1 ? "uint16" : "uint8") << ", 1 channel)";
  SAMP_CHECK(size.empty() || image.size() == size)
      << "eval: " << path << " is " << image.cols << "x" << image.rows << ", expected " << size.width
      << "x" << size.height;
  return image;
}

// Where a result keeps its files for `seq`.
std::string ResultFolder(const std::string& folder, const std::string& seq) {
  if (fs::exists(fs::path(folder) / "label_02" / (seq + ".txt"))) return folder;
  if (fs::exists(fs::path(folder) / seq / "label_02" / (seq + ".txt"))) return (fs::path(folder) / seq).string();
  return "";
}

// The mesh file of a track in a result folder (meshes/<seq>/ when the fit had
// several sequences, else meshes/); per-frame meshes first. "" when none exists.
std::string FindMeshFile(const std::string& folder, const std::string& seq, int track_id, int frame) {
  char per_frame[64], per_frame2[64];
  std::snprintf(per_frame, sizeof(per_frame), "track_%d_frame_%02d.ply", track_id, frame);
  std::snprintf(per_frame2, sizeof(per_frame2), "track_%d_%02d.ply", track_id, frame);
  for (const fs::path& meshes : {fs::path(folder) / "meshes" / seq, fs::path(folder) / "meshes"}) {
    for (const std::string& name : {std::string(per_frame), std::string(per_frame2),
                                    "track_" + std::to_string(track_id) + ".ply"}) {
      if (fs::exists(meshes / name)) return (meshes / name).string();
    }
  }
  return "";
}

// The fitted surfaces of one result folder. A single-frame fit has a shape per
// frame: when tracks.json holds per-frame shape codes, the surface of each frame
// is extracted from the model named there (fit/fit_output.h FittedSurface);
// otherwise the mesh files are used. Load() everything first; Get() is then
// const and thread-safe.
class ResultMeshes {
 public:
  explicit ResultMeshes(const std::string& folder) : folder_(folder) {
    const fs::path tracks = fs::path(folder) / "tracks.json";
    if (!fs::exists(tracks)) return;
    const TracksFile file = ReadTracksFile(tracks.string());
    for (const TracksFileSequence& sequence : file.sequences) {
      for (const TracksFileTrack& track : sequence.tracks) {
        if (!track.fit.single_frame) continue;
        for (const FrameFit& frame : track.fit.frames)
          codes_[Key(sequence.name, track.fit.track_id, frame.frame)] = frame.shape_code;
      }
    }
    if (!codes_.empty()) {
      model_path_ = file.model;
      SAMP_CHECK(!model_path_.empty()) << "eval: " << tracks.string()
                                       << " has per-frame shape codes but names no model";
    }
  }

  // Makes the surface of (seq, track, frame) available; throws when there is none.
  void Load(const std::string& seq, int track_id, int frame) {
    const std::string key = Key(seq, track_id, frame);
    if (codes_.count(key)) {
      if (!meshes_.count(key)) pending_codes_.insert(key);
      return;
    }
    const std::string path = FindMeshFile(folder_, seq, track_id, frame);
    SAMP_CHECK(!path.empty()) << "eval: no mesh for track " << track_id << " of " << seq << " in "
                              << folder_ << "/meshes";
    files_[key] = path;
    if (!meshes_.count(path)) meshes_[path] = std::make_unique<Mesh>(LoadMesh(path));
  }

  // Extracts the pending per-frame surfaces (in parallel).
  void Finish() {
    if (pending_codes_.empty()) return;
    if (!lookup_) {
      LogInfo() << "eval: extracting per-frame surfaces of " << folder_ << " from model " << model_path_;
      lookup_ = std::make_unique<ShapeLookup>(ShapeModel::Load(model_path_));
    }
    const std::vector<std::string> keys(pending_codes_.begin(), pending_codes_.end());
    std::vector<Mesh> surfaces(keys.size());
    tbb::parallel_for(size_t(0), keys.size(),
                      [&](size_t i) { surfaces[i] = FittedSurface(*lookup_, codes_.at(keys[i])); });
    for (size_t i = 0; i < keys.size(); ++i) meshes_[keys[i]] = std::make_unique<Mesh>(std::move(surfaces[i]));
    pending_codes_.clear();
  }

  const Mesh& Get(const std::string& seq, int track_id, int frame) const {
    const std::string key = Key(seq, track_id, frame);
    const auto file = files_.find(key);
    return *meshes_.at(file != files_.end() ? file->second : key);
  }

 private:
  static std::string Key(const std::string& seq, int track_id, int frame) {
    return seq + "/" + std::to_string(track_id) + "/" + std::to_string(frame);
  }
  std::string folder_;
  std::string model_path_;
  std::map<std::string, Eigen::VectorXd> codes_;
  std::set<std::string> pending_codes_;
  std::map<std::string, std::string> files_;
  std::map<std::string, std::unique_ptr<Mesh>> meshes_;
  std::unique_ptr<ShapeLookup> lookup_;
};

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

std::vector<CarFrameRecord> EvaluateSequence(const EvalOptions& options, const std::string& directory,
                                     const std::vector<EvalMethod>& methods,
                                     std::vector<std::unique_ptr<ResultMeshes>>* result_meshes,
                                     std::set<std::string>* tracks, std::vector<TrackingCounts>* tracking) {
  const SequenceFiles files = ListSequence(directory);
  const std::string seq = files.name;
  const SequenceLayout layout(directory, seq);
  const std::vector<ObjectLabel> gt_labels = ReadTrackingLabels(layout.GroundTruthLabels());
  std::map<int, std::vector<ObjectLabel>> gt_by_frame;
  for (const ObjectLabel& l : gt_labels) gt_by_frame[l.frame].push_back(l);
  if (gt_by_frame.empty()) {
    LogWarning() << "eval: " << directory << ": no ground-truth labels";
    return {};
  }
  // Image size from the first depth map.
  const cv::Mat first_depth =
      ReadPngOfType(layout.GroundTruthDepth(gt_by_frame.begin()->first), CV_16UC1, cv::Size());
  const StereoCalibration calibration =
      ReadCalibration(files.calibration, first_depth.cols, first_depth.rows);
  const PinholeCamera& camera = calibration.camera;
  const cv::Size size(camera.width, camera.height);

  // Each method's labels of this sequence, by frame.
  std::vector<std::map<int, std::vector<ObjectLabel>>> labels(methods.size());
  std::vector<std::string> result_folders(methods.size());
  for (size_t m = 0; m < methods.size(); ++m) {
    if (methods[m].name == kStereo) continue;
    if (methods[m].name == kDetections) {
      for (const auto& [frame, unused] : gt_by_frame) {
        const fs::path path = layout.Detections(frame);
        if (!fs::exists(path)) continue;
        for (ObjectLabel l : ReadLabels(path.string())) {
          if (!SameObjectType(l.type, "Car")) continue;
          l.frame = frame;
          labels[m][frame].push_back(l);
        }
      }
      continue;
    }
    result_folders[m] = ResultFolder(methods[m].folder, seq);
    if (result_folders[m].empty()) {
      LogWarning() << "eval: result '" << methods[m].name << "' has no label_02/" << seq
                   << ".txt in " << methods[m].folder << "; counted as no output for " << seq;
      continue;
    }
    for (const ObjectLabel& l :
         ReadTrackingLabels((fs::path(result_folders[m]) / "label_02" / (seq + ".txt")).string())) {
      if (SameObjectType(l.type, "Car")) labels[m][l.frame].push_back(l);
    }
  }

  // Per frame: the object map's segments and, per method, the IoU matches.
  struct FrameData {
    std::vector<std::vector<cv::Point>> segments;  // per truth
    std::vector<std::vector<int>> iou_match;       // per method: per truth, the index of its label or -1
  };
  std::map<int, FrameData> frame_data;
  for (const auto& [frame, truths] : gt_by_frame) {
    FrameData& fd = frame_data[frame];
    const cv::Mat object_map =
        ReadPngOfType(layout.GroundTruthObjectMap(frame), CV_8UC1, size);
    std::vector<Eigen::Vector4d> truth_boxes;
    for (const ObjectLabel& t : truths) truth_boxes.push_back(ProjectedBox(t, camera));
    fd.iou_match.resize(methods.size());
    for (size_t m = 0; m < methods.size(); ++m) {
      if (methods[m].name == kStereo) continue;
      std::vector<Eigen::Vector4d> boxes;
      for (const ObjectLabel& e : labels[m][frame]) boxes.push_back(ProjectedBox(e, camera));
      fd.iou_match[m] = MatchBoxes(truth_boxes, boxes, options.min_iou);
    }
    std::vector<std::vector<cv::Point>> segments(256);
    for (int v = 0; v < object_map.rows; ++v) {
      for (int u = 0; u < object_map.cols; ++u) {
        const uint8_t k = object_map.at<uint8_t>(v, u);
        if (k > 0) segments[k].emplace_back(u, v);
      }
    }
    for (const ObjectLabel& truth : truths) {
      SAMP_CHECK(truth.track_id >= 0 && truth.track_id < 255)
          << "eval: " << seq << " frame " << frame << ": ground-truth track id " << truth.track_id
          << " outside the object map's range 0..254";
      fd.segments.push_back(std::move(segments[truth.track_id + 1]));
    }
  }

  // Per-track matching: each true car gets the output track with which it
  // shares the most IoU-matched frames (one-to-one, Hungarian on the overlap).
  // A method without track ids (the detections) keeps the per-frame IoU match.
  std::vector<std::map<int, int>> track_of_car(methods.size());  // method: true id -> output track
  for (size_t m = 0; m < methods.size(); ++m) {
    if (methods[m].name == kStereo || methods[m].name == kDetections) continue;
    std::map<std::pair<int, int>, int> overlap;  // (true id, output track) -> frames
    std::set<int> car_ids, track_ids;
    for (const auto& [frame, truths] : gt_by_frame) {
      for (size_t t = 0; t < truths.size(); ++t) {
        const int e = frame_data[frame].iou_match[m][t];
        if (e < 0) continue;
        const int track = labels[m][frame][e].track_id;
        ++overlap[{truths[t].track_id, track}];
        car_ids.insert(truths[t].track_id);
        track_ids.insert(track);
      }
    }
    const std::vector<int> cars(car_ids.begin(), car_ids.end()), out_tracks(track_ids.begin(), track_ids.end());
    int most = 0;
    for (const auto& [pair, n] : overlap) most = std::max(most, n);
    // Every pair allowed (cost most + 1 - overlap): the assignment maximises the total overlap.
    std::vector<double> cost(cars.size() * out_tracks.size());
    for (size_t i = 0; i < cars.size(); ++i)
      for (size_t j = 0; j < out_tracks.size(); ++j) {
        const auto found = overlap.find({cars[i], out_tracks[j]});
        cost[i * out_tracks.size() + j] = most + 1 - (found == overlap.end() ? 0 : found->second);
      }
    const std::vector<int> assigned = SolveAssignment(cost, int(cars.size()), int(out_tracks.size()));
    for (size_t i = 0; i < cars.size(); ++i) {
      if (assigned[i] < 0 || !overlap.count({cars[i], out_tracks[assigned[i]]})) continue;
      track_of_car[m][cars[i]] = out_tracks[assigned[i]];
    }
  }

  // Per-frame matching (and the CLEAR-MOT counts): by the distance of the origins.
  std::vector<std::map<int, std::vector<int>>> frame_match(methods.size());  // method: frame -> per truth
  for (size_t m = 0; m < methods.size(); ++m) {
    if (methods[m].name == kStereo) continue;
    std::vector<TrackedBox> truth_boxes, output_boxes;
    std::vector<std::pair<int, int>> output_index;  // (frame, index in labels[m][frame])
    for (const auto& [frame, truths] : gt_by_frame) {
      for (size_t t = 0; t < truths.size(); ++t) {
        TrackedBox box;
        box.frame = frame;
        box.track_id = truths[t].track_id;
        box.position = truths[t].position;
        box.ignore = int(frame_data[frame].segments[t].size()) < options.min_segment_pixels;
        truth_boxes.push_back(box);
      }
      const std::vector<ObjectLabel>& estimates = labels[m][frame];
      for (size_t e = 0; e < estimates.size(); ++e) {
        output_boxes.push_back(TrackedBox{frame, estimates[e].track_id, estimates[e].position, false});
        output_index.push_back({frame, int(e)});
      }
    }
    const bool tracked = methods[m].name != kDetections;
    const std::vector<int> match = MatchTracks(truth_boxes, output_boxes, options.per_frame_distance,
                                               tracked ? &(*tracking)[m] : nullptr);
    size_t i = 0;
    for (const auto& [frame, truths] : gt_by_frame) {
      std::vector<int>& per_truth = frame_match[m][frame];
      for (size_t t = 0; t < truths.size(); ++t, ++i)
        per_truth.push_back(match[i] < 0 ? -1 : output_index[match[i]].second);
    }
  }

  // The evaluated car-frames.
  struct Work {
    CarFrameRecord record;
    std::vector<cv::Point> pixels;
    std::vector<const ObjectLabel*> matched[kNumMatchings];  // per method
  };
  std::vector<Work> work;
  for (const auto& [frame, truths] : gt_by_frame) {
    FrameData& fd = frame_data[frame];
    for (size_t t = 0; t < truths.size(); ++t) {
      const ObjectLabel& truth = truths[t];
      std::vector<cv::Point>& segment = fd.segments[t];
      if (int(segment.size()) < options.min_segment_pixels) continue;
      Work w;
      w.record.sequence = seq;
      w.record.track_id = truth.track_id;
      w.record.frame = frame;
      w.record.distance = truth.position.norm();
      w.record.segment_pixels = int(segment.size());
      w.record.true_size = Eigen::Vector3d(truth.height, truth.width, truth.length);
      w.pixels = std::move(segment);
      for (int k = 0; k < kNumMatchings; ++k) {
        w.record.methods[k].resize(methods.size());
        w.matched[k].assign(methods.size(), nullptr);
      }
      for (size_t m = 0; m < methods.size(); ++m) {
        if (methods[m].name == kStereo) {
          for (int k = 0; k < kNumMatchings; ++k) w.record.methods[k][m].matched = true;
          continue;
        }
        int index[kNumMatchings] = {fd.iou_match[m][t], frame_match[m][frame][t]};
        if (methods[m].name != kDetections && index[kPerTrack] >= 0) {
          const auto assigned = track_of_car[m].find(truth.track_id);
          if (assigned == track_of_car[m].end() ||
              labels[m][frame][index[kPerTrack]].track_id != assigned->second)
            index[kPerTrack] = -1;
        }
        for (int k = 0; k < kNumMatchings; ++k) {
          if (index[k] < 0) continue;
          const ObjectLabel& e = labels[m][frame][index[k]];
          w.matched[k][m] = &e;
          MethodCarFrame& r = w.record.methods[k][m];
          r.matched = true;
          r.output_track = e.track_id;
          r.translation_error = (e.position - truth.position).norm();
          r.yaw_error_deg = YawErrorDeg(e.rotation_y, truth.rotation_y);
          Eigen::Vector3d ray(truth.position.x(), 0.0, truth.position.z());
          ray = ray.norm() > 1e-9 ? Eigen::Vector3d(ray.normalized()) : Eigen::Vector3d::UnitZ();
          const Eigen::Vector3d error = e.position - truth.position;
          r.along_ray_offset = error.dot(ray);
          r.lateral_offset = error.dot(Eigen::Vector3d(ray.z(), 0.0, -ray.x()));
          r.vertical_offset = error.y();
          r.size = Eigen::Vector3d(e.height, e.width, e.length);
          if (methods[m].shape) (*result_meshes)[m]->Load(seq, e.track_id, frame);
        }
      }
      tracks->insert(seq + "/" + std::to_string(truth.track_id));
      work.push_back(std::move(w));
    }
  }

  // Shape scores, in parallel over car-frames (inputs read first).
  std::map<int, cv::Mat> depths, disparities;
  for (const Work& w : work) {
    const int f = w.record.frame;
    if (!depths.count(f)) {
      depths[f] = ReadPngOfType(layout.GroundTruthDepth(f), CV_16UC1, size);
      const fs::path disparity = layout.Disparity(f);
      if (options.stereo_baseline) {
        SAMP_CHECK(fs::exists(disparity)) << "eval: missing " << disparity.string()
                                          << " (needed by the stereo baseline)";
        disparities[f] = ReadDisparity(disparity.string(), size);
      }
    }
  }
  for (auto& meshes : *result_meshes) {
    if (meshes) meshes->Finish();
  }
  const double max_tau = options.taus.back();
  tbb::parallel_for(size_t(0), work.size(), [&](size_t i) {
    Work& w = work[i];
    const std::vector<Eigen::Vector3d> truth = BackProjectDepth(depths.at(w.record.frame), w.pixels, camera);
    w.record.num_true_points = int(truth.size());
    for (size_t m = 0; m < methods.size(); ++m) {
      for (int k = 0; k < kNumMatchings; ++k) {
        MethodCarFrame& r = w.record.methods[k][m];
        if (!methods[m].shape || !r.matched) continue;
        if (k == kPerFrame && w.matched[kPerTrack][m] == w.matched[kPerFrame][m] &&
            w.record.methods[kPerTrack][m].has_shape) {  // the same box: same scores
          r.num_estimated_points = w.record.methods[kPerTrack][m].num_estimated_points;
          r.scores = w.record.methods[kPerTrack][m].scores;
          r.has_shape = true;
          continue;
        }
        std::vector<Eigen::Vector3d> estimated;
        if (methods[m].name == kStereo) {
          const cv::Mat& disparity = disparities.at(w.record.frame);
          for (const cv::Point& p : w.pixels) {
            const float d = disparity.at<float>(p);
            if (d > 0.f) estimated.push_back(DisparityToPoint(p.x, p.y, d, calibration));
          }
        } else {
          const ObjectLabel& e = *w.matched[k][m];
          const Mesh& mesh = (*result_meshes)[m]->Get(seq, e.track_id, w.record.frame);
          estimated = RenderedPoints(mesh, CameraFromObject(e), w.pixels, camera);
        }
        r.num_estimated_points = int(estimated.size());
        const ShapeComparison comparison = CompareShapes(estimated, truth, max_tau);
        for (double tau : options.taus) r.scores.push_back(comparison.At(tau));
        r.has_shape = true;
      }
    }
  });
  std::vector<CarFrameRecord> records;
  for (Work& w : work) records.push_back(std::move(w.record));
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
  SAMP_CHECK(std::any_of(taus.begin(), taus.end(), [&](double t) { return std::abs(t - headline_tau) < 1e-9; }))
      << "eval: headline_tau " << headline_tau << " is not one of taus";
  SAMP_CHECK(distance_window > 0) << "eval: distance_window must be > 0";
  SAMP_CHECK(min_segment_pixels >= 1) << "eval: min_segment_pixels must be >= 1";
  SAMP_CHECK(min_iou > 0 && min_iou <= 1) << "eval: min_iou must be in (0, 1]";
  SAMP_CHECK(per_frame_distance > 0) << "eval: per_frame_distance must be > 0";
  SAMP_CHECK(num_threads >= 0) << "eval: num_threads must be >= 0";
}

std::string EvalOptions::ToJson() const {
  nlohmann::json results_json = nlohmann::json::array();
  for (const auto& [name, folder] : results) results_json.push_back({{"name", name}, {"folder", folder}});
  const nlohmann::json j = {{"sequences", sequences},
                            {"results", results_json},
                            {"taus", taus},
                            {"headline_tau", headline_tau},
                            {"distance_window", distance_window},
                            {"min_segment_pixels", min_segment_pixels},
                            {"min_iou", min_iou},
                            {"per_frame_distance", per_frame_distance},
                            {"stereo_baseline", stereo_baseline},
                            {"detection_baseline", detection_baseline}};
  return DumpJson(j, 2);
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

EvalResults ComputeEvaluation(const EvalOptions& options) {
  options.Check();
  EvalResults results;
  std::vector<EvalMethod>& methods = results.methods;
  if (options.stereo_baseline) methods.push_back({kStereo, "", true, false});
  if (options.detection_baseline) methods.push_back({kDetections, "", false, true});
  // A result without meshes (e.g. `samp fit --link-only`, another tracker's
  // labels) is evaluated for pose and tracking only.
  auto has_meshes = [](const std::string& folder) {
    if (fs::is_directory(fs::path(folder) / "meshes")) return true;
    for (const auto& entry : fs::directory_iterator(folder))
      if (entry.is_directory() && fs::is_directory(entry.path() / "meshes")) return true;
    return false;
  };
  // A result folder without labels of any given sequence (a wrong path, a
  // fit that wrote nothing) would score 0 % without a word: an error.
  std::vector<std::string> names;
  for (const std::string& sequence : options.sequences) names.push_back(ListSequence(sequence).name);
  for (const auto& [name, folder] : options.results) {
    // A lambda may not capture a structured binding in C++17 (clang refuses it).
    const std::string& result_folder = folder;
    const bool any = std::any_of(names.begin(), names.end(), [&](const std::string& seq) {
      return !ResultFolder(result_folder, seq).empty();
    });
    SAMP_CHECK(any) << "eval: result folder " << folder << " (" << name << ") has no results for any of the "
                    << names.size() << " sequence(s): no label_02/<seq>.txt or <seq>/label_02/<seq>.txt for "
                    << names.front() << (names.size() > 1 ? ", ..." : "");
  }
  for (const auto& [name, folder] : options.results) methods.push_back({name, folder, has_meshes(folder), true});

  std::vector<CarFrameRecord>& records = results.records;
  std::set<std::string> tracks;
  std::vector<TrackingCounts> tracking(methods.size());
  Progress progress("eval sequences", int64_t(options.sequences.size()));
  // --threads workers (0 = all cores) in a task arena of this call, as samp fit
  // and samp train do: no process-wide limit.
  tbb::task_arena arena(options.num_threads > 0 ? options.num_threads : tbb::task_arena::automatic);
  arena.execute([&] {
    for (const std::string& sequence : options.sequences) {
      std::vector<std::unique_ptr<ResultMeshes>> result_meshes(methods.size());
      for (size_t m = 0; m < methods.size(); ++m) {
        if (!methods[m].shape || methods[m].folder.empty()) continue;
        const std::string folder = ResultFolder(methods[m].folder, ListSequence(sequence).name);
        if (!folder.empty()) result_meshes[m] = std::make_unique<ResultMeshes>(folder);
      }
      std::vector<CarFrameRecord> r = EvaluateSequence(options, sequence, methods, &result_meshes, &tracks, &tracking);
      records.insert(records.end(), std::make_move_iterator(r.begin()), std::make_move_iterator(r.end()));
      progress.Tick();
    }
  });
  progress.Finish();

  EvalSummary& summary = results.summary;
  summary.taus = options.taus;
  summary.headline_tau = options.headline_tau;
  summary.num_sequences = int(options.sequences.size());
  summary.num_gt_car_frames = int(records.size());
  summary.num_gt_tracks = int(tracks.size());
  const size_t headline = summary.HeadlineIndex();

  double max_distance = 0.0;
  for (const CarFrameRecord& r : records) max_distance = std::max(max_distance, r.distance);
  const int num_windows = std::max(1, int(std::ceil(max_distance / options.distance_window)));
  results.num_windows = num_windows;
  for (int k = 0; k < kNumMatchings; ++k) {
    std::vector<MethodShapeResult>& shape_results = k == kPerTrack ? summary.shape : summary.shape_per_frame;
    std::vector<MethodPoseResult>& pose_results = k == kPerTrack ? summary.pose : summary.pose_per_frame;
    // Shape over the common set.
    auto in_common = [&](const CarFrameRecord& r, bool shape) {
      for (size_t m = 0; m < methods.size(); ++m) {
        if ((shape ? methods[m].shape : methods[m].pose) && !r.methods[k][m].matched) return false;
      }
      return true;
    };
    for (size_t m = 0; m < methods.size(); ++m) {
      if (!methods[m].shape) continue;
      MethodShapeResult s;
      s.method = methods[m].name;
      s.accuracy.assign(options.taus.size(), 0.0);
      s.completeness.assign(options.taus.size(), 0.0);
      s.f1.assign(options.taus.size(), 0.0);
      for (const CarFrameRecord& r : records) {
        if (r.methods[k][m].matched) ++s.num_matched;
        if (!in_common(r, true)) continue;
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
      shape_results.push_back(s);
    }
    // Pose over the common set, in distance windows.
    for (size_t m = 0; m < methods.size(); ++m) {
      if (!methods[m].pose) continue;
      MethodPoseResult p;
      p.method = methods[m].name;
      std::vector<std::vector<double>> translation(num_windows), yaw(num_windows);
      std::vector<double> all_translation, all_yaw, far_translation, far_yaw;
      for (const CarFrameRecord& r : records) {
        const MethodCarFrame& mr = r.methods[k][m];
        if (mr.matched) ++p.num_matched;
        if (!in_common(r, false)) continue;
        const int w = std::min(num_windows - 1, int(r.distance / options.distance_window));
        translation[w].push_back(mr.translation_error);
        yaw[w].push_back(mr.yaw_error_deg);
        all_translation.push_back(mr.translation_error);
        all_yaw.push_back(mr.yaw_error_deg);
        if (w > 0) {
          far_translation.push_back(mr.translation_error);
          far_yaw.push_back(mr.yaw_error_deg);
        }
      }
      for (int w = 0; w < num_windows; ++w) {
        p.windows.push_back(MakeWindow(w * options.distance_window, (w + 1) * options.distance_window,
                                       translation[w], yaw[w]));
      }
      p.all = MakeWindow(0.0, num_windows * options.distance_window, all_translation, all_yaw);
      p.beyond_first = MakeWindow(options.distance_window, num_windows * options.distance_window,
                                  far_translation, far_yaw);
      pose_results.push_back(p);
    }
  }
  // Tracking figures of the results (not of the baselines).
  for (size_t m = 0; m < methods.size(); ++m) {
    if (methods[m].name == kStereo || methods[m].name == kDetections) continue;
    summary.tracking.push_back({methods[m].name, tracking[m]});
  }
  // Per-car diagnostics by distance band (per-frame matching: every matched car-frame of the method).
  for (size_t m = 0; m < methods.size(); ++m) {
    if (!methods[m].pose) continue;
    for (int w = 0; w <= num_windows; ++w) {  // the last one: all distances
      DiagnosticsBand band;
      band.method = methods[m].name;
      band.min_distance = w < num_windows ? w * options.distance_window : 0.0;
      band.max_distance = w < num_windows ? (w + 1) * options.distance_window : num_windows * options.distance_window;
      std::vector<double> along, lateral, vertical, dh, dw, dl, f1;
      for (const CarFrameRecord& r : records) {
        const MethodCarFrame& mr = r.methods[kPerFrame][m];
        if (!mr.matched) continue;
        if (w < num_windows && std::min(num_windows - 1, int(r.distance / options.distance_window)) != w) continue;
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
      summary.diagnostics.push_back(band);
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
