#include "libsamp/core/json_text.h"
#include "libsamp/pipeline/fit_output.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/sdf/surface.h"

namespace samp {

AlignedBox FittedBox(const ShapeLookup& lookup, const Eigen::VectorXd& z) { return lookup.InsideBox(z); }

std::vector<std::string> GridLimitsReached(const AlignedBox& box, const GridSpec& grid) {
  std::vector<std::string> axes;
  if (box.IsEmpty()) return axes;
  const char* names[3] = {"length", "height", "width"};
  const Eigen::Vector3d lo = grid.MinCorner(), hi = grid.MaxCorner();
  const double tolerance = 0.5 * grid.voxel_size;
  for (int a = 0; a < 3; ++a)
    if (box.min[a] <= lo[a] + tolerance || box.max[a] >= hi[a] - tolerance) axes.push_back(names[a]);
  return axes;
}

std::vector<ObjectLabel> FitToLabels(const TrackFit& fit, const Track& track, const ShapeLookup& lookup) {
  SAMP_CHECK(fit.frames.size() == track.frames.size())
      << "track " << track.id << ": fit has " << fit.frames.size() << " frames, track "
      << track.frames.size();
  const PinholeCamera& camera = track.calibration.camera;
  std::vector<ObjectLabel> labels;
  for (size_t k = 0; k < fit.frames.size(); ++k) {
    const FrameFit& f = fit.frames[k];
    const TrackFrame& tf = track.frames[k];
    const Eigen::VectorXd& z = fit.single_frame ? f.shape_code : fit.shape_code;
    AlignedBox box = lookup.InsideBox(z);
    if (box.IsEmpty()) {
      box.min = box.max = Eigen::Vector3d::Zero();
    }
    const Eigen::Isometry3d camera_from_world = tf.world_from_camera.inverse();
    const Eigen::Isometry3d camera_from_object = camera_from_world * f.WorldFromObject();
    ObjectLabel label;
    label.frame = f.frame;
    label.track_id = fit.track_id;
    label.type = fit.type;
    label.truncation = tf.detection.truncation;
    label.occlusion = tf.detection.occlusion;
    label.position = camera_from_object.translation();
    label.rotation_y = WrapAngle(YawOfDirection(camera_from_object.linear() * Eigen::Vector3d::UnitX()));
    label.alpha = WrapAngle(label.rotation_y - std::atan2(label.position.x(), label.position.z()));
    const Eigen::Vector3d size = box.Size();
    label.length = size.x();
    label.height = size.y();
    label.width = size.z();
    label.score = tf.detection.score;
    // 2D box: the projected corners in front of the camera, clipped to the image.
    double x1 = 1e30, y1 = 1e30, x2 = -1e30, y2 = -1e30;
    int in_front = 0;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d corner((c & 1) ? box.max.x() : box.min.x(), (c & 2) ? box.max.y() : box.min.y(),
                                   (c & 4) ? box.max.z() : box.min.z());
      const Eigen::Vector3d p = camera_from_object * corner;
      if (p.z() <= 0.1) continue;
      ++in_front;
      const Eigen::Vector2d uv = camera.Project(p);
      x1 = std::min(x1, uv.x());
      y1 = std::min(y1, uv.y());
      x2 = std::max(x2, uv.x());
      y2 = std::max(y2, uv.y());
    }
    if (in_front == 0) {
      label.box_2d.setZero();
    } else {
      const double w = camera.width - 1.0, h = camera.height - 1.0;
      label.box_2d << std::clamp(x1, 0.0, w), std::clamp(y1, 0.0, h), std::clamp(x2, 0.0, w),
          std::clamp(y2, 0.0, h);
    }
    labels.push_back(label);
  }
  return labels;
}

Mesh FittedSurface(const ShapeLookup& lookup, const Eigen::VectorXd& z) {
  return ExtractSurface(lookup.grid(), lookup.Dense(z), 0.0);
}

PointCloud AlignedObservations(const TrackFit& fit) {
  PointCloud cloud;
  const int n = int(fit.frames.size());
  for (int k = 0; k < n; ++k) {
    const FrameFit& f = fit.frames[k];
    const Eigen::Isometry3d object_from_world = f.WorldFromObject().inverse();
    const double a = n > 1 ? double(k) / (n - 1) : 0.0;
    const Eigen::Matrix<uint8_t, 3, 1> color(uint8_t(255 * a), 64, uint8_t(255 * (1 - a)));
    for (const auto& p : f.points_in_world) {
      cloud.points.push_back((object_from_world * p).cast<float>());
      cloud.colors.push_back(color);
    }
  }
  return cloud;
}

namespace {
nlohmann::json Vec(const Eigen::VectorXd& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}
Eigen::VectorXd VectorOf(const JsonFields& fields, const std::string& key) {
  const std::vector<double> v = fields.Get<std::vector<double>>(key);
  return Eigen::Map<const Eigen::VectorXd>(v.data(), Eigen::Index(v.size()));
}
Eigen::Vector3d Vector3Of(const JsonFields& fields, const std::string& key) {
  const Eigen::VectorXd v = VectorOf(fields, key);
  SAMP_CHECK(v.size() == 3) << fields.Where() << ": key '" << key << "' must have 3 numbers, has " << v.size();
  return v;
}
}  // namespace

// The scalar keys of a track's record in tracks.json, listed once for
// TrackFitToJson and TrackFitFromJson (core/json_fields.h); the mode, the
// vectors and the arrays are written beside them.
static void OptionFields(OptionsJson& io, TrackFit& fit) {
  io("track_id", fit.track_id);
  io("sequence", fit.sequence);
  io("type", fit.type);
}

static void OptionFields(OptionsJson& io, FrameFit& f) {
  io("frame", f.frame);
  io("time", f.time);
  io("yaw", f.yaw);
  io("speed", f.speed);
  io("yaw_rate", f.yaw_rate);
  io("motion_model", f.motion_model);
  io("num_points", f.num_points);
  io("effective_points", f.effective_points);
  io("data_cost", f.data_cost);
}

static void OptionFields(OptionsJson& io, FitSummary& s) {
  io("initial_cost", s.initial_cost);
  io("final_cost", s.final_cost);
  io("num_iterations", s.num_iterations);
  io("seconds", s.seconds);
  io("usable", s.usable);
  io("association_notes", s.association_notes);
}

static void OptionFields(OptionsJson& io, SolveReport& r) {
  io("initial_cost", r.initial_cost);
  io("final_cost", r.final_cost);
  io("num_iterations", r.num_iterations);
  io("seconds", r.seconds);
  io("median_step_seconds", r.median_step_seconds);
  io("usable", r.usable);
  io("num_points", r.num_points);
  io("termination", r.termination);
}

nlohmann::json TrackFitToJson(const TrackFit& fit, const AlignedBox& box) {
  nlohmann::json j = OptionsToJson(fit);
  j["mode"] = fit.single_frame ? "single_frame" : "joint";
  j["shape_code"] = Vec(fit.shape_code);
  if (!box.IsEmpty()) {
    j["box_min"] = Vec(box.min);
    j["box_max"] = Vec(box.max);
  }
  nlohmann::json frames = nlohmann::json::array();
  for (const FrameFit& f : fit.frames) {
    nlohmann::json jf = OptionsToJson(f);
    jf["position_world"] = Vec(f.position);
    if (fit.single_frame) jf["shape_code"] = Vec(f.shape_code);
    frames.push_back(jf);
  }
  j["frames"] = frames;
  nlohmann::json s = OptionsToJson(fit.summary);
  nlohmann::json solves = nlohmann::json::array();
  for (const SolveReport& r : fit.summary.solves) solves.push_back(OptionsToJson(r));
  s["solves"] = solves;
  j["summary"] = s;
  return j;
}

TrackFit TrackFitFromJson(const JsonFields& j, AlignedBox* box) {
  TrackFit fit;
  OptionsFromJson(j, &fit);
  const std::string mode = j.Get<std::string>("mode");
  SAMP_CHECK(mode == "joint" || mode == "single_frame")
      << j.Where() << ": key 'mode' must be \"joint\" or \"single_frame\", got \"" << mode << "\"";
  fit.single_frame = mode == "single_frame";
  fit.shape_code = VectorOf(j, "shape_code");
  if (box != nullptr) {
    *box = AlignedBox();
    if (j.Has("box_min") || j.Has("box_max")) {
      box->min = Vector3Of(j, "box_min");
      box->max = Vector3Of(j, "box_max");
    }
  }
  for (const JsonFields& jf : j.Objects("frames")) {
    FrameFit f;
    OptionsFromJson(jf, &f);
    f.position = Vector3Of(jf, "position_world");
    if (fit.single_frame) f.shape_code = VectorOf(jf, "shape_code");
    fit.frames.push_back(std::move(f));
  }
  const JsonFields s = j.Object("summary");
  OptionsFromJson(s, &fit.summary);
  for (const JsonFields& js : s.Objects("solves")) {
    SolveReport r;
    OptionsFromJson(js, &r);
    fit.summary.solves.push_back(r);
  }
  return fit;
}

namespace {

constexpr const char* kDetectorModelOrigins[3] = {"self-calibration", "file", "none"};

bool IsDetectorModelOrigin(const std::string& origin) {
  return std::find(std::begin(kDetectorModelOrigins), std::end(kDetectorModelOrigins), origin) !=
         std::end(kDetectorModelOrigins);
}

}  // namespace

nlohmann::json DetectorModelRecordToJson(const TracksFileDetectorModel& record, const std::string& path) {
  SAMP_CHECK(IsDetectorModelOrigin(record.origin))
      << path << ": detector model origin '" << record.origin << "' is not one of self-calibration, file, none";
  nlohmann::json j = nlohmann::json::object();
  j["origin"] = record.origin;
  if (record.origin == "file") j["file"] = record.file;
  if (record.origin == "none") {
    j["reason"] = record.reason;
  } else {
    j["model"] = ParseJson(record.model.ToJson(), path + ": detector_model.model");
  }
  return j;
}

TracksFileDetectorModel DetectorModelRecordFromJson(const JsonFields& j) {
  TracksFileDetectorModel record;
  j.Read("origin", &record.origin);
  SAMP_CHECK(IsDetectorModelOrigin(record.origin))
      << j.Where() << ": key 'origin' must be \"self-calibration\", \"file\" or \"none\", got \"" << record.origin
      << "\"";
  if (record.origin == "file") j.Read("file", &record.file);
  if (record.origin == "none") {
    j.Read("reason", &record.reason);
  } else {
    // Checked as a detector model file is (format, version, every key and range).
    record.model = DetectorNoiseModelFromJson(DumpJson(j.At("model")), j.Where() + ".model");
  }
  return record;
}

void WriteTracksFile(const std::string& path, const TracksFile& file) {
  nlohmann::json tracks_json;
  tracks_json["model"] = file.model;
  if (!file.detector_model.origin.empty())
    tracks_json["detector_model"] = DetectorModelRecordToJson(file.detector_model, path);
  tracks_json["sequences"] = nlohmann::json::array();
  for (const TracksFileSequence& r : file.sequences) {
    nlohmann::json js;
    js["directory"] = r.directory;
    js["name"] = r.name;
    js["ok"] = r.ok;
    if (!r.ok) js["error"] = r.error;
    js["input"] = r.input;
    js["input_messages"] = r.input_messages;
    if (r.ok) js["tracking"] = r.tracking;
    js["tracks"] = nlohmann::json::array();
    for (const TracksFileTrack& t : r.tracks) {
      nlohmann::json jt = TrackFitToJson(t.fit, t.box);
      if (!t.mesh.empty()) jt["mesh"] = t.mesh;
      if (!t.points.empty()) jt["points"] = t.points;
      if (!t.at_grid_limit.empty()) jt["at_grid_limit"] = t.at_grid_limit;
      js["tracks"].push_back(std::move(jt));
    }
    js["failed_tracks"] = r.failed_tracks;
    tracks_json["sequences"].push_back(js);
  }
  WriteTextFileAtomically(path, DumpJson(tracks_json, 2) + "\n");
}

TracksFile ReadTracksFile(const std::string& path) {
  const nlohmann::json json = ReadJsonFile(path);
  const JsonFields j(json, path);
  TracksFile file;
  j.Read("model", &file.model);
  if (j.Has("detector_model")) file.detector_model = DetectorModelRecordFromJson(j.Object("detector_model"));
  for (const JsonFields& js : j.Objects("sequences")) {
    TracksFileSequence r;
    js.Read("directory", &r.directory);
    js.Read("name", &r.name);
    js.Read("ok", &r.ok);
    if (!r.ok) js.Read("error", &r.error);
    js.Read("input", &r.input);
    js.Read("input_messages", &r.input_messages);
    if (r.ok) r.tracking = js.At("tracking");
    for (const JsonFields& jt : js.Objects("tracks")) {
      TracksFileTrack t;
      t.fit = TrackFitFromJson(jt, &t.box);
      if (jt.Has("mesh") || jt.Has("points")) {
        jt.Read("mesh", &t.mesh);
        jt.Read("points", &t.points);
      }
      if (jt.Has("at_grid_limit")) jt.Read("at_grid_limit", &t.at_grid_limit);
      r.tracks.push_back(std::move(t));
    }
    js.Read("failed_tracks", &r.failed_tracks);
    file.sequences.push_back(std::move(r));
  }
  return file;
}

std::string FitTracksPath(const std::string& out) { return (std::filesystem::path(out) / "tracks.json").string(); }

std::string FitLabelsPath(const std::string& out, const std::string& seq) {
  return (std::filesystem::path(out) / "label_02" / (seq + ".txt")).string();
}

std::string FitMeshStem(const std::string& seq, int track_id, bool per_sequence_folder) {
  return (per_sequence_folder ? "meshes/" + seq + "/" : std::string("meshes/")) + "track_" + std::to_string(track_id);
}

}  // namespace samp
