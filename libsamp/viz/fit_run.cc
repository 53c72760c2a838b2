#include "libsamp/viz/fit_run.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/core/ply_io.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/sequence.h"
#include "libsamp/data/sequence_layout.h"
#include "libsamp/model/shape_model.h"
#include "libsamp/pipeline/fit_config.h"
#include "libsamp/pipeline/fit_output.h"
#include "libsamp/scan/mesh_io.h"
#include "libsamp/viz/image.h"
#include "libsamp/viz/inspect.h"
#include "libsamp/viz/view_option_table.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

Eigen::Isometry3d CameraFromLabel(const ObjectLabel& label) { return PoseFromYaw(label.position, label.rotation_y); }

// Per-vertex distances of `mesh` (moved by `transform`) to the nearest of `points`.
std::vector<float> VertexDistances(const Mesh& mesh, const Eigen::Isometry3d& transform,
                                   const std::vector<Eigen::Vector3f>& points) {
  std::vector<Eigen::Vector3f> moved(mesh.vertices.size());
  for (size_t i = 0; i < moved.size(); ++i) moved[i] = (transform * mesh.vertices[i].cast<double>()).cast<float>();
  std::vector<double> d = NearestDistanceEach(moved, points);
  return std::vector<float>(d.begin(), d.end());
}

void AttachGroundTruth(const std::string& directory, const std::string& name, const LoadFitRunOptions& options,
                       SequenceView* sequence) {
  const SequenceLayout layout(directory, name);  // docs/synthetic.md, "Ground truth"
  const std::string labels_path = layout.GroundTruthLabels();
  if (!fs::exists(labels_path)) return;
  std::map<int, GroundTruthCarView> cars;
  for (const ObjectLabel& label : ReadTrackingLabels(labels_path)) {
    if (label.track_id < 0) continue;
    GroundTruthCarView& car = cars[label.track_id];
    car.id = label.track_id;
    car.size = Eigen::Vector3d(label.length, label.height, label.width);
    auto wfc = sequence->world_from_camera.find(label.frame);
    const Eigen::Isometry3d world_from_camera =
        wfc != sequence->world_from_camera.end() ? wfc->second : Eigen::Isometry3d::Identity();
    car.world_from_object[label.frame] = world_from_camera * CameraFromLabel(label);
  }
  for (auto& [id, car] : cars) {
    const std::string mesh_path = layout.GroundTruthMesh(id);
    if (fs::exists(mesh_path)) car.mesh = LoadMesh(mesh_path);
    sequence->ground_truth.push_back(std::move(car));
  }
  // Each fitted track: the true car whose origin is nearest over the common
  // frames (median distance, at most 3 m); errors at the middle common frame.
  for (TrackView& track : sequence->tracks) {
    const GroundTruthCarView* best = nullptr;
    double best_distance = 3.0;
    std::vector<int> best_frames;
    for (const GroundTruthCarView& car : sequence->ground_truth) {
      std::vector<double> distances;
      std::vector<int> frames;
      for (const TrackFrameView& f : track.frames) {
        auto it = car.world_from_object.find(f.frame);
        if (it == car.world_from_object.end()) continue;
        distances.push_back((it->second.translation() - f.world_from_object.translation()).norm());
        frames.push_back(f.frame);
      }
      if (distances.empty()) continue;
      std::nth_element(distances.begin(), distances.begin() + distances.size() / 2, distances.end());
      const double median = distances[distances.size() / 2];
      if (median < best_distance) best_distance = median, best = &car, best_frames = frames;
    }
    if (best == nullptr) continue;
    track.gt_track_id = best->id;
    if (best->mesh.Empty() || track.mesh.Empty()) continue;
    const int frame = best_frames[best_frames.size() / 2];
    const TrackFrameView* f = nullptr;
    for (const TrackFrameView& g : track.frames) {
      if (g.frame == frame) f = &g;
    }
    const std::vector<Eigen::Vector3f> samples = SampleSurface(best->mesh, options.error_samples, 1);
    const Eigen::Isometry3d gt_from_fit = best->world_from_object.at(frame).inverse() * f->world_from_object;
    track.vertex_errors = VertexDistances(track.mesh, gt_from_fit, samples);
    track.error_frame = frame;
  }
}

}  // namespace

Eigen::Isometry3d PoseFromYaw(const Eigen::Vector3d& position, double yaw) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  pose.translation() = position;
  return pose;
}

const TrackView* SequenceView::FindTrack(int id) const {
  for (const TrackView& t : tracks) {
    if (t.id == id) return &t;
  }
  return nullptr;
}

int FitRunView::NumTracks() const {
  int n = 0;
  for (const SequenceView& s : sequences) n += int(s.tracks.size());
  return n;
}

void LoadFitRunOptions::Check() const {
  LoadFitRunOptionTable().Check(*this);
}

int FrameIndexOfColor(uint8_t red, uint8_t green, uint8_t blue, int num_frames) {
  if (green != 64 || num_frames <= 0) return -1;
  // The writer's formula (AlignedObservations): a = k / (n - 1), red = uint8(255 a),
  // blue = uint8(255 (1 - a)). Invert from red and check both channels exactly.
  const int n = num_frames;
  if (n == 1) return (red == 0 && blue == 255) ? 0 : -1;
  const int guess = int(std::lround(double(red) * (n - 1) / 255.0));
  for (int k = std::max(0, guess - 2); k <= std::min(n - 1, guess + 2); ++k) {
    const double a = double(k) / (n - 1);
    if (uint8_t(255 * a) == red && uint8_t(255 * (1 - a)) == blue) return k;
  }
  return -1;
}

FitRunView LoadFitRun(const std::string& output_dir, const LoadFitRunOptions& options) {
  options.Check();
  const fs::path out(output_dir);
  // tracks.json and config.json through their one reader (pipeline/fit_output.h,
  // pipeline/fit_config.h): a missing key is an error naming the file and key.
  const TracksFile tracks_file = ReadTracksFile((out / "tracks.json").string());
  FitRunView run;
  run.output_dir = output_dir;
  run.model_path = tracks_file.model;
  // The tracking label files of config.json, one per sequence directory.
  std::map<std::string, std::string> tracking_labels;
  const fs::path config_path = out / "config.json";
  if (fs::exists(config_path)) {
    const FitConfig config = ReadFitConfig(config_path.string());
    const std::vector<std::string>& dirs = config.options.sequences;
    const std::vector<std::string>& labels = config.options.tracking_labels;
    for (size_t i = 0; i < labels.size() && i < dirs.size(); ++i) tracking_labels[dirs[i]] = labels[i];
  }
  // Sigmas of the model for the code in sigmas; a missing model only loses that.
  Eigen::VectorXd sigmas;
  if (fs::exists(run.model_path)) {
    try {
      sigmas = ShapeModel::Load(run.model_path).eigenvalues.cwiseMax(0.0).cwiseSqrt();
    } catch (const std::exception& e) {
      LogWarning() << "model " << run.model_path << " not read (codes shown unscaled): " << e.what();
    }
  } else {
    LogInfo() << "model " << run.model_path << " not found: codes shown unscaled";
  }

  for (const TracksFileSequence& js : tracks_file.sequences) {
    if (!js.ok || js.tracks.empty()) continue;
    SequenceView sequence;
    sequence.directory = js.directory;
    sequence.name = js.name;
    sequence.error_tau = options.error_tau;
    const SequenceFiles files = ListSequence(sequence.directory);
    // The image size: from the first left image, else not known (KITTI's).
    int width = 0, height = 0;
    for (const FrameFiles& f : files.frames) {
      sequence.frames.push_back(f.frame);
      if (!f.image_left.empty()) {
        if (options.read_images) sequence.left_images[f.frame] = f.image_left;
        if (sequence.left_images.size() == 1) {
          const RgbImage first = ReadPng(f.image_left);
          width = first.width, height = first.height;
        }
      }
    }
    sequence.camera = ReadCalibration(files.calibration, width, height).camera;
    std::vector<Eigen::Isometry3d> poses;
    if (!files.poses.empty()) poses = ReadPoses(files.poses);
    for (int frame : sequence.frames) {
      sequence.world_from_camera[frame] =
          frame >= 0 && size_t(frame) < poses.size() ? poses[size_t(frame)] : Eigen::Isometry3d::Identity();
    }
    // Detections: the tracking labels given to the fit, else detections/ per frame.
    std::map<std::pair<int, int>, ObjectLabel> labelled;  // (frame, track id)
    std::map<int, std::vector<ObjectLabel>> detections;   // per frame
    auto labels_it = tracking_labels.find(sequence.directory);
    if (labels_it != tracking_labels.end() && !labels_it->second.empty()) {
      for (const ObjectLabel& l : ReadTrackingLabels(labels_it->second)) labelled[{l.frame, l.track_id}] = l;
    } else {
      for (const FrameFiles& f : files.frames) {
        if (!f.detections.empty()) detections[f.frame] = ReadLabels(f.detections);
      }
    }

    for (const TracksFileTrack& jt : js.tracks) {
      TrackView track;
      track.id = jt.fit.track_id;
      track.type = jt.fit.type;
      track.mode = jt.fit.single_frame ? "single_frame" : "joint";
      track.shape_code = jt.fit.shape_code;
      if (sigmas.size() == track.shape_code.size() && (sigmas.array() > 0).all()) {
        track.code_in_sigmas = track.shape_code.cwiseQuotient(sigmas);
      }
      track.box = jt.box;
      track.initial_cost = jt.fit.summary.initial_cost;
      track.final_cost = jt.fit.summary.final_cost;
      track.num_iterations = jt.fit.summary.num_iterations;
      track.seconds = jt.fit.summary.seconds;
      for (const FrameFit& jf : jt.fit.frames) {
        TrackFrameView f;
        f.frame = jf.frame;
        f.time = jf.time;
        f.world_from_object = PoseFromYaw(jf.position, jf.yaw);
        f.speed = jf.speed;
        f.yaw_rate = jf.yaw_rate;
        f.motion_model = jf.motion_model;
        f.num_points = jf.num_points;
        f.data_cost = jf.data_cost;
        const Eigen::Isometry3d world_from_camera = sequence.world_from_camera.count(f.frame)
                                                        ? sequence.world_from_camera.at(f.frame)
                                                        : Eigen::Isometry3d::Identity();
        const ObjectLabel* detection = nullptr;
        auto l = labelled.find({f.frame, track.id});
        if (l != labelled.end()) {
          detection = &l->second;
        } else if (detections.count(f.frame)) {
          // The detection nearest to the fitted pose (within 3 m): the one the tracker linked.
          double best = 3.0;
          for (const ObjectLabel& d : detections.at(f.frame)) {
            if (!SameObjectType(d.type, track.type)) continue;
            const double dist = ((world_from_camera * d.position) - f.world_from_object.translation()).norm();
            if (dist < best) best = dist, detection = &d;
          }
        }
        if (detection != nullptr) {
          f.has_detection = true;
          f.world_from_detection = world_from_camera * CameraFromLabel(*detection);
          f.detection_size = Eigen::Vector3d(detection->length, detection->height, detection->width);
          f.detection_box_2d = detection->box_2d;
        }
        track.frames.push_back(std::move(f));
      }
      if (!jt.mesh.empty()) {
        const std::string mesh_path = (out / jt.mesh).string();
        try {
          track.mesh = LoadMesh(mesh_path);
        } catch (const Error& e) {
          // An empty fitted surface is written as a PLY without triangles.
          LogWarning() << "track " << track.id << ": " << e.what();
        }
      }
      if (!jt.points.empty()) {
        const std::string points_path = (out / jt.points).string();
        const PointCloud cloud = ReadPointCloudPly(points_path);
        SAMP_CHECK(cloud.colors.size() == cloud.points.size())
            << points_path << ": the aligned points carry no frame colours";
        const int n = int(track.frames.size());
        for (size_t i = 0; i < cloud.points.size(); ++i) {
          const auto& c = cloud.colors[i];
          const int k = FrameIndexOfColor(c[0], c[1], c[2], n);
          SAMP_CHECK(k >= 0) << points_path << ": point " << i << " has colour (" << int(c[0]) << ", " << int(c[1])
                             << ", " << int(c[2]) << "), which no frame of the " << n << " has";
          TrackFrameView& f = track.frames[size_t(k)];
          f.points_in_world.push_back((f.world_from_object * cloud.points[i].cast<double>()).cast<float>());
        }
      }
      sequence.tracks.push_back(std::move(track));
    }
    std::sort(sequence.tracks.begin(), sequence.tracks.end(),
              [](const TrackView& a, const TrackView& b) { return a.id < b.id; });
    // Road plane: planes/ of the first frame that has one, else through the cars' bottoms.
    sequence.ground_plane_source.clear();
    for (const FrameFiles& f : files.frames) {
      if (f.plane.empty()) continue;
      const Eigen::Vector4d p = ReadPlane(f.plane);
      const Eigen::Isometry3d& wfc = sequence.world_from_camera.at(f.frame);
      const Eigen::Vector3d n = wfc.linear() * p.head<3>();
      sequence.ground_plane_in_world << n, p[3] - n.dot(wfc.translation());
      sequence.ground_plane_source =
          std::string(SequenceLayout::kPlanesFolder) + "/" + SequenceLayout::FrameFileName(sequence.name, f.frame, ".txt");
      break;
    }
    if (sequence.ground_plane_source.empty()) {
      double y = 0.0;
      int count = 0;
      for (const TrackView& t : sequence.tracks) {
        for (const TrackFrameView& f : t.frames) y += f.world_from_object.translation().y(), ++count;
      }
      sequence.ground_plane_in_world = Eigen::Vector4d(0, -1, 0, count ? y / count : 1.65);
      sequence.ground_plane_source = "fitted cars";
    }
    if (options.read_ground_truth) AttachGroundTruth(sequence.directory, sequence.name, options, &sequence);
    run.sequences.push_back(std::move(sequence));
  }
  return run;
}

}  // namespace samp
