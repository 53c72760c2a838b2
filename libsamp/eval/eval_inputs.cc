#include "libsamp/eval/eval_inputs.h"

#include <tbb/parallel_for.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/data/detection_files.h"
#include "libsamp/data/kitti_tracking.h"
#include "libsamp/data/sequence.h"
#include "libsamp/model/shape_lookup.h"
#include "libsamp/model/shape_model.h"
#include "libsamp/pipeline/fit_output.h"
#include "libsamp/scan/mesh_io.h"

namespace samp::eval {
namespace {

namespace fs = std::filesystem;

// The mesh file of a track in a result folder (meshes/<seq>/ when the fit had
// several sequences, else meshes/). "" when none exists.
std::string FindMeshFile(const std::string& folder, const std::string& seq, int track_id) {
  for (const bool per_sequence : {true, false}) {
    const fs::path path = fs::path(folder) / (FitMeshStem(seq, track_id, per_sequence) + ".ply");
    if (fs::exists(path)) return path.string();
  }
  return "";
}

// The detections of the ground truth's frames (SEQ/detections), cars only.
std::map<int, std::vector<ObjectLabel>> ReadDetections(const SequenceInputs& inputs) {
  std::map<int, std::vector<ObjectLabel>> labels;
  for (const auto& [frame, unused] : inputs.gt_by_frame) {
    const fs::path path = inputs.layout.Detections(frame);
    if (!fs::exists(path)) continue;
    for (ObjectLabel l : ReadLabels(path.string())) {
      if (!SameObjectType(l.type, "Car")) continue;
      l.frame = frame;
      labels[frame].push_back(l);
    }
  }
  return labels;
}

// A result's car labels of the sequence (none, with a warning, when it has no output for it).
std::map<int, std::vector<ObjectLabel>> ReadResultLabels(const EvalMethod& method, const std::string& seq) {
  std::map<int, std::vector<ObjectLabel>> labels;
  const std::string folder = ResultFolder(method.folder, seq);
  if (folder.empty()) {
    LogWarning() << "eval: result '" << method.name << "' has no label_02/" << seq << ".txt in " << method.folder
                 << "; counted as no output for " << seq;
    return labels;
  }
  for (const ObjectLabel& l : ReadTrackingLabels(FitLabelsPath(folder, seq))) {
    if (SameObjectType(l.type, "Car")) labels[l.frame].push_back(l);
  }
  return labels;
}

// Per truth of `frame`, its object-map segment.
std::vector<std::vector<cv::Point>> ReadSegments(const SequenceInputs& inputs, int frame) {
  const cv::Mat object_map = ReadPngOfType(inputs.layout.GroundTruthObjectMap(frame), CV_8UC1, inputs.size);
  std::vector<std::vector<cv::Point>> by_value(256);
  for (int v = 0; v < object_map.rows; ++v) {
    for (int u = 0; u < object_map.cols; ++u) {
      const uint8_t k = object_map.at<uint8_t>(v, u);
      if (k > 0) by_value[k].emplace_back(u, v);
    }
  }
  std::vector<std::vector<cv::Point>> segments;
  for (const ObjectLabel& truth : inputs.gt_by_frame.at(frame)) {
    SAMP_CHECK(truth.track_id >= 0 && truth.track_id < 255)
        << "eval: " << inputs.seq << " frame " << frame << ": ground-truth track id " << truth.track_id
        << " outside the object map's range 0..254";
    segments.push_back(std::move(by_value[truth.track_id + 1]));
  }
  return segments;
}

}  // namespace

std::string ResultFolder(const std::string& folder, const std::string& seq) {
  if (fs::exists(FitLabelsPath(folder, seq))) return folder;
  const std::string per_sequence = (fs::path(folder) / seq).string();
  if (fs::exists(FitLabelsPath(per_sequence, seq))) return per_sequence;
  return "";
}

ResultMeshes::ResultMeshes(const std::string& folder) : folder_(folder) {
  const std::string tracks = FitTracksPath(folder);
  if (!fs::exists(tracks)) return;
  const TracksFile file = ReadTracksFile(tracks);
  for (const TracksFileSequence& sequence : file.sequences) {
    for (const TracksFileTrack& track : sequence.tracks) {
      if (!track.fit.single_frame) continue;
      for (const FrameFit& frame : track.fit.frames)
        codes_[Key(sequence.name, track.fit.track_id, frame.frame)] = frame.shape_code;
    }
  }
  if (!codes_.empty()) {
    model_path_ = file.model;
    SAMP_CHECK(!model_path_.empty()) << "eval: " << tracks << " has per-frame shape codes but names no model";
  }
}

ResultMeshes::~ResultMeshes() = default;

void ResultMeshes::Load(const std::string& seq, int track_id, int frame) {
  const std::string key = Key(seq, track_id, frame);
  if (codes_.count(key)) {
    if (!meshes_.count(key)) pending_codes_.insert(key);
    return;
  }
  const std::string path = FindMeshFile(folder_, seq, track_id);
  SAMP_CHECK(!path.empty()) << "eval: no mesh for track " << track_id << " of " << seq << " in " << folder_
                            << "/meshes";
  files_[key] = path;
  if (!meshes_.count(path)) meshes_[path] = std::make_unique<Mesh>(LoadMesh(path));
}

void ResultMeshes::Finish() {
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

const Mesh& ResultMeshes::Get(const std::string& seq, int track_id, int frame) const {
  const std::string key = Key(seq, track_id, frame);
  const auto file = files_.find(key);
  return *meshes_.at(file != files_.end() ? file->second : key);
}

std::string ResultMeshes::Key(const std::string& seq, int track_id, int frame) {
  return seq + "/" + std::to_string(track_id) + "/" + std::to_string(frame);
}

cv::Mat ReadPngOfType(const std::string& path, int type, const cv::Size& size) {
  SAMP_CHECK(fs::exists(path)) << "eval: missing file " << path;
  cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  SAMP_CHECK(!image.empty()) << "eval: cannot decode " << path;
  SAMP_CHECK(image.type() == type) << "eval: " << path << " has the wrong pixel type (expected "
                                   << (type == CV_16UC1 ? "uint16" : "uint8") << ", 1 channel)";
  SAMP_CHECK(size.empty() || image.size() == size)
      << "eval: " << path << " is " << image.cols << "x" << image.rows << ", expected " << size.width << "x"
      << size.height;
  return image;
}

bool IsKittiTrackingSequence(const std::string& directory) {
  return ListSequence(directory).layout == SequenceFiles::Layout::kKittiTracking;
}

namespace {

// samp's layout: ground truth with depth and object maps (gt/).
bool LoadSampGroundTruth(const EvalOptions& options, const SequenceFiles& files, SequenceInputs* inputs) {
  inputs->layout = SequenceLayout(inputs->directory, files.name);
  for (const ObjectLabel& l : ReadTrackingLabels(inputs->layout.GroundTruthLabels()))
    inputs->gt_by_frame[l.frame].push_back(l);
  if (inputs->gt_by_frame.empty()) return false;
  // The image size from the first depth map.
  const cv::Mat first_depth =
      ReadPngOfType(inputs->layout.GroundTruthDepth(inputs->gt_by_frame.begin()->first), CV_16UC1, cv::Size());
  inputs->calibration = ReadCalibration(files.calibration, first_depth.cols, first_depth.rows);
  inputs->size = cv::Size(inputs->calibration.camera.width, inputs->calibration.camera.height);
  for (const auto& [frame, truths] : inputs->gt_by_frame) {
    inputs->segments[frame] = ReadSegments(*inputs, frame);
    for (const std::vector<cv::Point>& segment : inputs->segments[frame])
      inputs->evaluated[frame].push_back(int(segment.size()) >= options.min_segment_pixels);
  }
  return true;
}

// KITTI tracking's layout: ROOT/label_02/<seq>.txt (rectified camera 0, as the
// labels samp fit writes for such a sequence), no maps; a true car is evaluated
// by its box height, occlusion and truncation.
bool LoadKittiGroundTruth(const EvalOptions& options, const SequenceFiles& files, SequenceInputs* inputs) {
  KittiTrackingLayout layout("", "");
  SAMP_CHECK(KittiTrackingLayout::FromSequenceFolder(inputs->directory, &layout)) << inputs->directory;
  const std::string labels = layout.Labels();
  SAMP_CHECK(fs::is_regular_file(labels)) << "eval: KITTI tracking sequence " << inputs->directory << " has no "
                                          << labels << " (ground truth: the training split)";
  for (const ObjectLabel& l : ReadTrackingLabels(labels)) {
    if (SameObjectType(l.type, "Car")) inputs->gt_by_frame[l.frame].push_back(l);
  }
  if (inputs->gt_by_frame.empty()) return false;
  SAMP_CHECK(!files.frames.empty()) << "eval: " << inputs->directory << ": no images";
  const PngHeader image = ReadPngHeader(files.frames.front().image_left);
  inputs->calibration = ReadCalibration(files.calibration, int(image.width), int(image.height));
  inputs->size = cv::Size(int(image.width), int(image.height));
  inputs->has_maps = false;
  for (const auto& [frame, truths] : inputs->gt_by_frame) {
    for (const ObjectLabel& t : truths) {
      inputs->evaluated[frame].push_back(t.box_2d[3] - t.box_2d[1] >= options.min_box_height_px &&
                                         t.occlusion <= options.max_occlusion &&
                                         t.truncation <= options.max_truncation);
    }
  }
  return true;
}

// The detections of a KITTI tracking sequence (EvalOptions::detections_path),
// cars only, in the labels' frame.
std::map<int, std::vector<ObjectLabel>> ReadKittiDetections(const EvalOptions& options, const SequenceInputs& inputs) {
  std::map<int, std::vector<ObjectLabel>> labels;
  const fs::path path = fs::is_directory(options.detections_path)
                            ? fs::path(options.detections_path) / (inputs.seq + ".txt")
                            : fs::path(options.detections_path);
  SAMP_CHECK(fs::is_regular_file(path)) << "eval: no detections of " << inputs.seq << ": " << path.string()
                                        << " does not exist";
  for (const ObjectLabel& l : ReadDetectionFile(path.string(), SniffDetectionFormat(path.string()))) {
    if (SameObjectType(l.type, "Car")) labels[l.frame].push_back(l);
  }
  return labels;
}

}  // namespace

bool LoadSequenceInputs(const EvalOptions& options, const std::string& directory,
                        const std::vector<EvalMethod>& methods, SequenceInputs* inputs) {
  const SequenceFiles files = ListSequence(directory);
  inputs->directory = directory;
  inputs->seq = files.name;
  const bool kitti = files.layout == SequenceFiles::Layout::kKittiTracking;
  if (!(kitti ? LoadKittiGroundTruth(options, files, inputs) : LoadSampGroundTruth(options, files, inputs))) {
    LogWarning() << "eval: " << directory << ": no ground-truth labels";
    return false;
  }
  inputs->labels.assign(methods.size(), {});
  for (size_t m = 0; m < methods.size(); ++m) {
    if (methods[m].name == kStereo) continue;
    if (methods[m].name == kDetections) {
      inputs->labels[m] = kitti ? ReadKittiDetections(options, *inputs) : ReadDetections(*inputs);
    } else {
      inputs->labels[m] = ReadResultLabels(methods[m], inputs->seq);
    }
  }
  return true;
}

}  // namespace samp::eval
