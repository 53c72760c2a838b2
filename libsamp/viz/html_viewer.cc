#include "libsamp/core/json_text.h"
#include "libsamp/viz/html_viewer.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/viz/html_assets.h"
#include "libsamp/viz/image.h"
#include "libsamp/viz/view_option_table.h"

namespace samp {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

template <typename T>
std::string Base64Of(const std::vector<T>& values) {
  return Base64Encode(values.data(), values.size() * sizeof(T));
}

// Position and rotation (x y z qx qy qz qw) of a pose, as floats.
void AppendPose(const Eigen::Isometry3d& pose, std::vector<float>* out) {
  const Eigen::Quaterniond q(pose.linear());
  const Eigen::Vector3d t = pose.translation();
  for (double v : {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()}) out->push_back(float(v));
}

Json MeshJson(const Mesh& mesh) {
  std::vector<float> positions;
  positions.reserve(3 * mesh.vertices.size());
  for (const auto& v : mesh.vertices) positions.insert(positions.end(), {v.x(), v.y(), v.z()});
  std::vector<uint32_t> indices;
  indices.reserve(3 * mesh.triangles.size());
  for (const auto& t : mesh.triangles) indices.insert(indices.end(), {uint32_t(t[0]), uint32_t(t[1]), uint32_t(t[2])});
  return {{"positions", Base64Of(positions)}, {"indices", Base64Of(indices)},
          {"num_vertices", mesh.vertices.size()}, {"num_triangles", mesh.triangles.size()}};
}

Json ColorJson(Rgb c) { return {c.r, c.g, c.b}; }

// The page: style, three.js, the data, the viewer.
std::string Page(const std::string& title, const Json& data, const std::vector<std::string>& scripts) {
  SAMP_CHECK(HtmlViewerAvailable())
      << "this samp was built without three.js: install Debian's libjs-three (tools/install_deps.sh) and "
         "rebuild to write HTML viewers";
  std::string json = DumpJson(data);
  // Inside <script> "</" would end the element; "<\/" is the same JSON string.
  for (size_t i = 0; (i = json.find("</", i)) != std::string::npos; i += 3) json.replace(i, 2, "<\\/");
  std::string escaped_title;
  for (char c : title) {
    if (c == '<') escaped_title += "&lt;";
    else if (c == '>') escaped_title += "&gt;";
    else if (c == '&') escaped_title += "&amp;";
    else escaped_title += c;
  }
  std::string html;
  html.reserve(json.size() + (1 << 20));
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" + escaped_title +
          "</title>\n<meta name=\"generator\" content=\"samp (three.js r" + EmbeddedThreeRevision() + ")\">\n";
  html += "<script>window.sampErrors = [];\n"
          "window.addEventListener('error', function (e) { window.sampErrors.push(String(e.message)); });\n"
          "(function () { var original = console.error; console.error = function () {\n"
          "  window.sampErrors.push(Array.prototype.join.call(arguments, ' ')); original.apply(console, arguments); };\n"
          "})();</script>\n";
  html += "<style>\n" + internal::EmbeddedAsset("viewer.css") + "\n</style>\n</head>\n<body>\n";
  html += "<script id=\"samp-data\" type=\"application/json\">" + json + "</script>\n";
  for (const std::string& name : {std::string("three.min.js"), std::string("OrbitControls.js")}) {
    html += "<script>/* " + name + " (three.js r" + EmbeddedThreeRevision() + ", MIT licence) */\n" +
            internal::EmbeddedAsset(name) + "\n</script>\n";
  }
  for (const std::string& name : scripts) {
    const std::string content = internal::EmbeddedAsset(name);
    SAMP_CHECK(!content.empty()) << "the viewer asset " << name << " was not embedded at build time";
    html += "<script>/* " + name + " */\n" + content + "\n</script>\n";
  }
  html += "</body>\n</html>\n";
  return html;
}

// Every `step`-th of n items when subsampling to at most `max` (0 = all).
std::vector<size_t> EvenSubsample(size_t n, int max) {
  std::vector<size_t> keep;
  if (max <= 0 || n <= size_t(max)) {
    keep.resize(n);
    for (size_t i = 0; i < n; ++i) keep[i] = i;
    return keep;
  }
  for (int i = 0; i < max; ++i) keep.push_back(size_t((uint64_t(i) * n) / size_t(max)));
  return keep;
}

Json TrackJson(const TrackView& track, size_t index, const FitHtmlOptions& options) {
  Json j;
  j["id"] = track.id;
  j["type"] = track.type;
  j["mode"] = track.mode;
  j["color"] = ColorJson(PaletteColor(int(index)));
  std::vector<int> frames;
  std::vector<float> poses, detections, speeds, yaw_rates, costs;
  std::vector<std::string> motion_models;
  std::vector<int> num_points;
  // Points relative to the frame's fitted origin, int16 with a per-frame scale.
  std::vector<int16_t> points;
  std::vector<uint32_t> offsets = {0};
  std::vector<float> scales;
  for (const TrackFrameView& f : track.frames) {
    frames.push_back(f.frame);
    AppendPose(f.world_from_object, &poses);
    if (f.has_detection) {
      AppendPose(f.world_from_detection, &detections);
      for (int a = 0; a < 3; ++a) detections.push_back(float(f.detection_size[a]));
    } else {
      detections.insert(detections.end(), 10, std::nanf(""));
    }
    speeds.push_back(float(f.speed));
    yaw_rates.push_back(float(f.yaw_rate));
    costs.push_back(float(f.data_cost));
    motion_models.push_back(f.motion_model);
    num_points.push_back(f.num_points);
    const Eigen::Vector3d origin = f.world_from_object.translation();
    const std::vector<size_t> keep = EvenSubsample(f.points_in_world.size(), options.max_points_per_frame);
    double max_abs = 1e-3;
    for (size_t i : keep) max_abs = std::max(max_abs, (f.points_in_world[i].cast<double>() - origin).cwiseAbs().maxCoeff());
    const double scale = max_abs / 32767.0;
    for (size_t i : keep) {
      const Eigen::Vector3d d = (f.points_in_world[i].cast<double>() - origin) / scale;
      for (int a = 0; a < 3; ++a) points.push_back(int16_t(std::lround(std::clamp(d[a], -32767.0, 32767.0))));
    }
    offsets.push_back(uint32_t(points.size() / 3));
    scales.push_back(float(scale));
  }
  j["frames"] = frames;
  j["poses"] = Base64Of(poses);
  j["detections"] = Base64Of(detections);
  j["speed"] = speeds;
  j["yaw_rate"] = yaw_rates;
  j["data_cost"] = costs;
  j["motion_model"] = motion_models;
  j["num_points"] = num_points;
  j["points"] = {{"data", Base64Of(points)}, {"offsets", offsets}, {"scales", scales}};
  if (!track.mesh.Empty()) {
    j["mesh"] = MeshJson(track.mesh);
    if (track.vertex_errors.size() == track.mesh.vertices.size()) {
      j["mesh"]["errors"] = Base64Of(track.vertex_errors);
      j["error_frame"] = track.error_frame;
    }
  }
  if (!track.box.IsEmpty()) {
    j["box_min"] = {track.box.min.x(), track.box.min.y(), track.box.min.z()};
    j["box_max"] = {track.box.max.x(), track.box.max.y(), track.box.max.z()};
  }
  std::vector<double> code(track.shape_code.data(), track.shape_code.data() + track.shape_code.size());
  j["shape_code"] = code;
  if (track.code_in_sigmas.size() > 0) {
    j["code_in_sigmas"] = std::vector<double>(track.code_in_sigmas.data(),
                                              track.code_in_sigmas.data() + track.code_in_sigmas.size());
  }
  j["initial_cost"] = track.initial_cost;
  j["final_cost"] = track.final_cost;
  j["num_iterations"] = track.num_iterations;
  j["seconds"] = track.seconds;
  j["gt_track_id"] = track.gt_track_id;
  return j;
}

}  // namespace

std::string Base64Encode(const void* data, size_t size) {
  static const char kTable[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* bytes = static_cast<const uint8_t*>(data);
  std::string out;
  out.reserve(4 * ((size + 2) / 3));
  size_t i = 0;
  for (; i + 2 < size; i += 3) {
    const uint32_t v = (uint32_t(bytes[i]) << 16) | (uint32_t(bytes[i + 1]) << 8) | bytes[i + 2];
    out += kTable[(v >> 18) & 63], out += kTable[(v >> 12) & 63], out += kTable[(v >> 6) & 63], out += kTable[v & 63];
  }
  if (i + 1 == size) {
    const uint32_t v = uint32_t(bytes[i]) << 16;
    out += kTable[(v >> 18) & 63], out += kTable[(v >> 12) & 63], out += "==";
  } else if (i + 2 == size) {
    const uint32_t v = (uint32_t(bytes[i]) << 16) | (uint32_t(bytes[i + 1]) << 8);
    out += kTable[(v >> 18) & 63], out += kTable[(v >> 12) & 63], out += kTable[(v >> 6) & 63], out += '=';
  }
  return out;
}

bool HtmlViewerAvailable() { return !internal::EmbeddedAsset("three.min.js").empty(); }
std::string EmbeddedThreeRevision() { return internal::EmbeddedThreeRevisionString(); }

void FitHtmlOptions::Check() const {
  FitHtmlOptionTable().Check(*this);
}

void InspectHtmlOptions::Check() const {
  SAMP_CHECK(max_components >= 0) << "InspectHtmlOptions.max_components must be >= 0";
  SAMP_CHECK(slider_sigmas > 0) << "InspectHtmlOptions.slider_sigmas must be > 0";
}

std::string FitViewerHtml(const FitRunView& run, const FitHtmlOptions& options) {
  options.Check();
  Json data;
  data["kind"] = "fit";
  data["output_dir"] = fs::path(run.output_dir).filename().string();
  data["model"] = fs::path(run.model_path).filename().string();
  data["sequences"] = Json::array();
  for (const SequenceView& sequence : run.sequences) {
    Json js;
    js["name"] = sequence.name;
    js["frames"] = sequence.frames;
    std::vector<float> ego;
    for (int frame : sequence.frames) AppendPose(sequence.world_from_camera.at(frame), &ego);
    js["ego"] = Base64Of(ego);
    js["camera"] = {{"fx", sequence.camera.fx}, {"fy", sequence.camera.fy}, {"cx", sequence.camera.cx},
                    {"cy", sequence.camera.cy}, {"width", sequence.camera.width}, {"height", sequence.camera.height}};
    const Eigen::Vector4d& g = sequence.ground_plane_in_world;
    js["ground_plane"] = {g[0], g[1], g[2], g[3]};
    js["ground_plane_source"] = sequence.ground_plane_source;
    js["error_tau"] = sequence.error_tau;
    js["tracks"] = Json::array();
    for (size_t t = 0; t < sequence.tracks.size(); ++t) js["tracks"].push_back(TrackJson(sequence.tracks[t], t, options));
    js["ground_truth"] = Json::array();
    for (const GroundTruthCarView& car : sequence.ground_truth) {
      std::vector<int> frames;
      std::vector<float> poses;
      for (const auto& [frame, pose] : car.world_from_object) frames.push_back(frame), AppendPose(pose, &poses);
      js["ground_truth"].push_back(
          {{"id", car.id}, {"size", {car.size.x(), car.size.y(), car.size.z()}}, {"frames", frames},
           {"poses", Base64Of(poses)}});
    }
    data["sequences"].push_back(js);
  }
  const std::string title = options.title.empty() ? "samp fit: " + data["output_dir"].get<std::string>() : options.title;
  data["title"] = title;
  return Page(title, data, {"viewer_common.js", "fit_viewer.js"});
}

void WriteFitViewer(const std::string& path, const FitRunView& run, const FitHtmlOptions& options) {
  const std::string html = FitViewerHtml(run, options);
  WriteTextFileAtomically(path, html);
}

std::string InspectViewerHtml(const ShapeModel& model, const InspectHtmlOptions& options) {
  options.Check();
  model.Check();
  const int r = options.max_components > 0 ? std::min(options.max_components, model.NumComponents())
                                           : model.NumComponents();
  Json data;
  data["kind"] = "inspect";
  data["model"] = fs::path(options.model_path).filename().string();
  const GridSpec& grid = model.grid;
  data["grid"] = {{"origin", {grid.origin.x(), grid.origin.y(), grid.origin.z()}},
                  {"voxel_size", grid.voxel_size},
                  {"dims", {grid.dims.x(), grid.dims.y(), grid.dims.z()}}};
  std::vector<float> mean(model.mean.data(), model.mean.data() + model.mean.size());
  data["mean"] = Base64Of(mean);
  data["components"] = Json::array();
  std::vector<double> sigmas;
  for (int i = 0; i < r; ++i) {
    std::vector<float> w(model.components.col(i).data(), model.components.col(i).data() + model.components.rows());
    data["components"].push_back(Base64Of(w));
    sigmas.push_back(std::sqrt(std::max(0.0, model.eigenvalues[i])));
  }
  data["sigmas"] = sigmas;
  std::vector<double> explained;
  const double total = model.total_variance > 0 ? model.total_variance : model.eigenvalues.sum();
  for (int i = 0; i < r; ++i) explained.push_back(total > 0 ? model.eigenvalues[i] / total : 0.0);
  data["explained"] = explained;
  data["slider_sigmas"] = options.slider_sigmas;
  data["num_training_shapes"] = model.training_shapes.size();
  const std::string title =
      options.title.empty() ? "samp inspect: " + data["model"].get<std::string>() : options.title;
  data["title"] = title;
  return Page(title, data, {"MarchingCubes.js", "viewer_common.js", "inspect_viewer.js"});
}

void WriteInspectViewer(const std::string& path, const ShapeModel& model, const InspectHtmlOptions& options) {
  WriteTextFileAtomically(path, InspectViewerHtml(model, options));
}

}  // namespace samp
