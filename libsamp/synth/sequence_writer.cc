#include "libsamp/synth/sequence_writer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/core/json_text.h"
#include "libsamp/core/ply_io.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/kitti_tracking.h"
#include "libsamp/data/sequence_layout.h"
#include "libsamp/data/stereo.h"
#include "libsamp/scan/embree_scene.h"
#include "libsamp/synth/procedural.h"
#include "libsamp/synth/shading.h"

namespace samp::synth {
namespace {

namespace fs = std::filesystem;
using procedural::Mix;

void WriteImage(const std::string& path, const cv::Mat& image) {
  WriteFileAtomically(path, [&](const std::string& temporary) {
    SAMP_CHECK(cv::imwrite(temporary, image)) << "cannot write image " << path;
  });
}

// The 3D box label of a car in the camera of one frame, 2D box from its projected vertices.
// Returns false when no vertex lies in front of the camera or the box misses the image.
bool MakeLabel(const SceneCar& car, int frame, const Eigen::Isometry3d& camera_from_world,
               const PinholeCamera& camera, ObjectLabel* label) {
  const Eigen::Isometry3d camera_from_object =
      camera_from_world * WorldFromObject(car.states[frame]);
  AlignedBox box;
  for (const Eigen::Vector3f& vertex : car.car->mesh.vertices) {
    const Eigen::Vector3d p = camera_from_object * vertex.cast<double>();
    if (p.z() < 0.1) continue;
    const Eigen::Vector2d uv = camera.Project(p);
    box.Extend(Eigen::Vector3d(uv.x(), uv.y(), 0.0));
  }
  if (box.IsEmpty()) return false;
  const double x1 = std::clamp(box.min.x(), 0.0, camera.width - 1.0);
  const double y1 = std::clamp(box.min.y(), 0.0, camera.height - 1.0);
  const double x2 = std::clamp(box.max.x(), 0.0, camera.width - 1.0);
  const double y2 = std::clamp(box.max.y(), 0.0, camera.height - 1.0);
  if (x2 <= x1 || y2 <= y1) return false;
  const double full_area = std::max(1e-9, (box.max.x() - box.min.x()) * (box.max.y() - box.min.y()));
  label->frame = frame;
  label->track_id = car.track_id;
  label->type = "Car";
  label->truncation = std::clamp(1.0 - (x2 - x1) * (y2 - y1) / full_area, 0.0, 1.0);
  label->occlusion = 0;
  label->box_2d = Eigen::Vector4d(x1, y1, x2, y2);
  label->height = car.height;
  label->width = car.width;
  label->length = car.length;
  label->position = camera_from_object.translation();
  const Eigen::Vector3d x_axis = camera_from_object.linear().col(0);
  label->rotation_y = std::atan2(-x_axis.z(), x_axis.x());
  label->alpha = WrapAngle(label->rotation_y - std::atan2(label->position.x(), label->position.z()));
  label->score = 1.0;
  return true;
}

cv::Mat TrueDisparityWithNoise(const SynthOptions& options, const RenderBuffers& left,
                               int num_statics, uint64_t noise_seed) {
  Random rng(noise_seed);
  const double fb = options.focal_px * options.baseline;
  cv::Mat disparity(left.height, left.width, CV_32FC1, cv::Scalar(0.f));
  for (int v = 0; v < left.height; ++v) {
    for (int u = 0; u < left.width; ++u) {
      const size_t pixel = size_t(v) * left.width + u;
      const float z = left.depth[pixel];
      if (!std::isfinite(z) || z <= 0.f) continue;
      const double truth = fb / z;
      double value;
      const double draw = rng.Uniform(0.0, 1.0);
      if (draw < options.invalid_fraction) {
        value = 0.0;
      } else if (draw < options.invalid_fraction + options.outlier_fraction) {
        value = rng.Uniform(0.5, std::min(255.0, std::max(2.0, 2.0 * truth)));
      } else {
        const bool on_car = left.mesh_index[pixel] >= num_statics;
        value = truth + rng.Normal(on_car ? options.car_disparity_sigma_px : options.disparity_sigma_px);
      }
      if (value < 0.5 || value >= 255.9) value = 0.0;  // below 0.5 px: invalid (z > 770 m)
      disparity.at<float>(v, u) = float(value);
    }
  }
  return disparity;
}

// Calibration and the camera poses, relative to frame 0 (KITTI: frame 0 =
// identity); the rendering frame differs from it by the sway of frame 0 (street).
void WriteCameras(const SynthOptions& options, const Scene& scene, const SequenceLayout& layout) {
  StereoCalibration calibration;
  calibration.camera = MakeCamera(options);
  calibration.baseline = options.baseline;
  WriteCalibration(layout.Calibration(), calibration);
  const Eigen::Isometry3d output_from_world = scene.world_from_camera[0].inverse();
  std::vector<Eigen::Isometry3d> output_poses;
  for (const Eigen::Isometry3d& pose : scene.world_from_camera) output_poses.push_back(output_from_world * pose);
  WritePoses(layout.Poses(), output_poses);
}

// The ground-truth meshes (object frame) and the cars' descriptions for cars.json.
nlohmann::json WriteCars(const Scene& scene, const SequenceLayout& layout) {
  nlohmann::json cars_json = nlohmann::json::array();
  for (const SceneCar& car : scene.cars) {
    WritePly(layout.GroundTruthMesh(car.track_id), car.car->mesh);
    nlohmann::json entry = {{"track_id", car.track_id},
                            {"car", car.car->name},
                            {"motion", MotionName(car.motion)},
                            {"speed", car.speed},
                            {"yaw_rate", car.yaw_rate},
                            {"paint", car.paint_name},
                            {"length", car.length},
                            {"height", car.height},
                            {"width", car.width},
                            {"distance_at_middle_frame", car.target_distance}};
    if (scene.street) entry["parked"] = car.parked;
    cars_json.push_back(entry);
  }
  return cars_json;
}

struct StereoView {
  RenderBuffers left_buffers, right_buffers;
  cv::Mat left_image, right_image;
};

// The left and right views of frame t. Street: one world-frame scene for both
// cameras and the shadow rays; clean: the meshes placed in each camera.
StereoView RenderStereo(const SynthOptions& options, const Scene& scene, int t, uint64_t seed) {
  const PinholeCamera camera = MakeCamera(options);
  const ShadingPreset preset = scene.street ? StreetShading(options) : CleanShading();
  Eigen::Isometry3d right_from_left = Eigen::Isometry3d::Identity();
  right_from_left.translation() = Eigen::Vector3d(-options.baseline, 0.0, 0.0);
  const Eigen::Isometry3d& world_from_left = scene.world_from_camera[t];
  const Eigen::Isometry3d world_from_right = world_from_left * right_from_left.inverse();
  StereoView view;
  std::unique_ptr<EmbreeScene> embree;
  if (preset.buffers == ShadingPreset::BufferFrame::kWorld) {
    std::vector<Mesh> car_meshes(scene.cars.size());
    std::vector<const Mesh*> meshes;
    for (const StaticMesh& m : scene.statics) meshes.push_back(&m.mesh);
    for (size_t c = 0; c < scene.cars.size(); ++c) {
      car_meshes[c] = scene.cars[c].car->mesh;
      car_meshes[c].Transform(Eigen::Affine3d(WorldFromObject(scene.cars[c].states[t])));
      meshes.push_back(&car_meshes[c]);
    }
    embree = std::make_unique<EmbreeScene>(meshes);
    view.left_buffers = RenderFromScene(*embree, camera, world_from_left);
    view.right_buffers = RenderFromScene(*embree, camera, world_from_right);
  } else {
    const Eigen::Isometry3d camera_from_world = world_from_left.inverse();
    std::vector<PlacedMesh> left, right;
    for (const StaticMesh& m : scene.statics) left.push_back({&m.mesh, camera_from_world});
    for (const SceneCar& car : scene.cars) {
      left.push_back({&car.car->mesh, camera_from_world * WorldFromObject(car.states[t])});
    }
    for (const PlacedMesh& placed : left) right.push_back({placed.mesh, right_from_left * placed.camera_from_object});
    view.left_buffers = Render(camera, left);
    view.right_buffers = Render(camera, right);
  }
  view.left_image = ShadeView(preset, options, scene, t, world_from_left, camera, view.left_buffers, embree.get(),
                              Mix(seed, uint64_t(1000 + 2 * t)));
  view.right_image = ShadeView(preset, options, scene, t, world_from_right, camera, view.right_buffers,
                               embree.get(), Mix(seed, uint64_t(1001 + 2 * t)));
  return view;
}

// Per car its visible pixels in the left view.
std::vector<int> VisiblePixels(const Scene& scene, const RenderBuffers& left) {
  const int num_statics = int(scene.statics.size());
  std::vector<int> visible(scene.cars.size(), 0);
  for (size_t pixel = 0; pixel < size_t(left.height) * left.width; ++pixel)
    if (left.mesh_index[pixel] >= num_statics) ++visible[left.mesh_index[pixel] - num_statics];
  return visible;
}

// Ground truth of frame t: depth (uint16, 1/256 m) and object map (uint8,
// track_id + 1). Returns per car its visible pixels.
std::vector<int> WriteGroundTruthMaps(const Scene& scene, const RenderBuffers& left, const SequenceLayout& layout,
                                      int t) {
  const int num_statics = int(scene.statics.size());
  cv::Mat depth(left.height, left.width, CV_16UC1, cv::Scalar(0));
  cv::Mat object_map(left.height, left.width, CV_8UC1, cv::Scalar(0));
  for (int v = 0; v < left.height; ++v) {
    for (int u = 0; u < left.width; ++u) {
      const size_t pixel = size_t(v) * left.width + u;
      const float z = left.depth[pixel];
      if (std::isfinite(z) && z > 0.f && z < 255.99f) {
        depth.at<uint16_t>(v, u) = uint16_t(std::lround(double(z) * 256.0));
      }
      const int index = left.mesh_index[pixel];
      if (index >= num_statics) object_map.at<uint8_t>(v, u) = uint8_t(scene.cars[index - num_statics].track_id + 1);
    }
  }
  WriteImage(layout.GroundTruthDepth(t), depth);
  WriteImage(layout.GroundTruthObjectMap(t), object_map);
  return VisiblePixels(scene, left);
}

// Disparity quality on the car pixels (what the stereo baseline and the fitter see).
struct DisparityQuality {
  double error_sum = 0.0;
  int64_t valid = 0, car_pixels = 0;

  void Add(const SynthOptions& options, const RenderBuffers& left, int num_statics, const cv::Mat& disparity) {
    const double fb = options.focal_px * options.baseline;
    for (int v = 0; v < left.height; ++v) {
      for (int u = 0; u < left.width; ++u) {
        const size_t pixel = size_t(v) * left.width + u;
        if (left.mesh_index[pixel] < num_statics) continue;
        ++car_pixels;
        const float d = disparity.at<float>(v, u);
        if (!(d > 0.f)) continue;
        ++valid;
        error_sum += std::abs(double(d) - fb / double(left.depth[pixel]));
      }
    }
  }
};

// The road plane n . x + d = 0 (n = (0, -1, 0), d = camera height in the
// rendering frame) in the camera of frame t.
void WriteRoadPlane(const SynthOptions& options, const Scene& scene, const SequenceLayout& layout, int t) {
  const Eigen::Vector3d n_world(0.0, -1.0, 0.0);
  const Eigen::Vector3d n_camera = scene.world_from_camera[t].linear().transpose() * n_world;
  const double d_camera = options.camera_height + n_world.dot(scene.world_from_camera[t].translation());
  WritePlane(layout.Plane(t), Eigen::Vector4d(n_camera.x(), n_camera.y(), n_camera.z(), d_camera));
}

// The true labels of the visible cars of frame t (appended to *gt_labels) and
// the detector's detections of them and of the clutter.
std::vector<ObjectLabel> DetectFrame(const Scene& scene, int t, const PinholeCamera& camera,
                                     const std::vector<int>& visible, StereoDetectorModel* detector,
                                     std::vector<ObjectLabel>* gt_labels, SynthSequenceInfo* info) {
  const Eigen::Isometry3d camera_from_world = scene.world_from_camera[t].inverse();
  std::vector<ObjectLabel> detections;
  for (size_t c = 0; c < scene.cars.size(); ++c) {
    ObjectLabel truth;
    if (visible[c] == 0 || !MakeLabel(scene.cars[c], t, camera_from_world, camera, &truth)) continue;
    gt_labels->push_back(truth);
    ObjectLabel det;
    if (detector->Detect(scene.cars[c].track_id, t, truth, visible[c], camera, &det)) detections.push_back(det);
  }
  if (!scene.clutter.empty()) {
    std::vector<ClutterCandidate> candidates = scene.clutter;
    for (size_t i = 0; i < candidates.size(); ++i) {
      PlanarState state;
      state.position = scene.clutter[i].position;
      state.heading = scene.clutter_heading[i];
      const Eigen::Isometry3d camera_from_object = camera_from_world * WorldFromObject(state);
      candidates[i].position = camera_from_object.translation();
      candidates[i].rotation_y = YawOfDirection(camera_from_object.linear().col(0));
    }
    const std::vector<ObjectLabel> false_positives = detector->FalsePositives(t, candidates, camera);
    info->num_false_positives += int(false_positives.size());
    detections.insert(detections.end(), false_positives.begin(), false_positives.end());
  }
  info->num_detections += int(detections.size());
  return detections;
}

// gt/cars.json: the sequence's scene, its disparity quality and its cars.
nlohmann::json SceneJson(const SynthOptions& options, const Scene& scene, const SynthSequenceInfo& info,
                         nlohmann::json cars_json) {
  nlohmann::json scene_json = {{"sequence", info.name},
                               {"seed", options.seed},
                               {"scene", scene.street ? "street" : "clean"},
                               {"ego_speed", scene.ego_speed},
                               {"ego_yaw_rate", scene.ego_yaw_rate},
                               {"frame_rate_hz", options.frame_rate_hz},
                               {"num_frames", options.num_frames},
                               {"depth_png", "uint16, depth_m = value / 256, 0 = no surface"},
                               {"obj_map_png", "uint8, 0 = background, track_id + 1 = car"},
                               {"car_disparity_mae_px", info.car_disparity_mae_px},
                               {"car_disparity_valid_fraction", info.car_disparity_valid_fraction},
                               {"num_false_positives", info.num_false_positives},
                               {"cars", std::move(cars_json)}};
  if (scene.street) {
    constexpr double kDeg = 180.0 / kPi;
    scene_json["street"] = {{"lanes_per_direction", scene.layout.lanes_per_direction},
                            {"lane_width", scene.layout.lane_width},
                            {"parking_lanes", scene.layout.parking.size()},
                            {"intersection", scene.layout.has_intersection},
                            {"intersection_z", scene.layout.intersection_z},
                            {"sun_elevation_deg", std::asin(-scene.lighting.to_sun.y()) * kDeg},
                            {"ego_pitch_sway_deg", scene.sway.pitch_amplitude * kDeg},
                            {"ego_roll_sway_deg", scene.sway.roll_amplitude * kDeg},
                            {"ego_pitch_offset_deg", scene.sway.pitch_offset * kDeg}};
  }
  return scene_json;
}

// The scene in KITTI tracking's own layout (data/kitti_tracking.h) below
// OUT/training: the same images and detector draws as samp's layout, a
// calibration with all matrices (MakeKittiTrackingCalibration), the oxts of
// the ego trajectory, the ground truth as label_02/<seq>.txt and the
// detections as KITTI tracking lines (track id -1) in OUT/detections/<seq>.txt,
// both in rectified camera 0 as KITTI's (moved by -t2 from the rendering
// camera 2). No disparity, planes or ground-truth maps: KITTI has none.
SynthSequenceInfo WriteKittiTrackingSequence(const SynthOptions& options, const Scene& scene, int sequence_index,
                                             Progress* progress) {
  const PinholeCamera camera = MakeCamera(options);
  SynthSequenceInfo info;
  char name[16];
  std::snprintf(name, sizeof(name), "%04d", options.first_sequence + sequence_index);
  info.name = name;
  const KittiTrackingLayout layout((fs::path(options.output_folder) / "training").string(), info.name);
  info.folder = layout.LeftImageFolder();
  info.num_cars = int(scene.cars.size());
  const uint64_t seed = Mix(options.seed, uint64_t(sequence_index));
  StereoCalibration stereo;
  stereo.camera = camera;
  stereo.baseline = options.baseline;
  const KittiTrackingCalibration calibration = MakeKittiTrackingCalibration(stereo);
  const Eigen::Vector3d to_label_frame = -calibration.Camera2FromRectified0();
  WriteKittiTrackingCalibration(layout.Calibration(), calibration);
  WriteOxts(layout.Oxts(), OxtsFromCameraPoses(scene.world_from_camera, calibration, OxtsOrigin(), options.frame_rate_hz));
  std::vector<ObjectLabel> gt_labels, detections;
  StereoDetectorModel detector(options.detector, Mix(seed, 5000));
  for (int t = 0; t < options.num_frames; ++t) {
    const StereoView view = RenderStereo(options, scene, t, seed);
    WriteImage(layout.LeftImage(t), view.left_image);
    WriteImage(layout.RightImage(t), view.right_image);
    const std::vector<int> visible = VisiblePixels(scene, view.left_buffers);
    for (ObjectLabel d : DetectFrame(scene, t, camera, visible, &detector, &gt_labels, &info)) {
      d.frame = t;
      d.track_id = -1;
      detections.push_back(MoveLabel(d, to_label_frame));
    }
    if (progress) progress->Tick();
  }
  for (ObjectLabel& label : gt_labels) label = MoveLabel(label, to_label_frame);
  info.num_gt_labels = int(gt_labels.size());
  WriteTrackingLabels(layout.Labels(), gt_labels);
  WriteTrackingLabels((fs::path(options.output_folder) / "detections" / (info.name + ".txt")).string(), detections);
  return info;
}

}  // namespace

SynthSequenceInfo WriteSequence(const SynthOptions& options, const Scene& scene, int sequence_index,
                                Progress* progress) {
  if (options.layout == SynthLayout::kKittiTracking)
    return WriteKittiTrackingSequence(options, scene, sequence_index, progress);
  const PinholeCamera camera = MakeCamera(options);
  SynthSequenceInfo info;
  char name[16];
  std::snprintf(name, sizeof(name), "%06d", options.first_sequence + sequence_index);
  info.name = name;
  info.folder = (fs::path(options.output_folder) / info.name).string();
  info.num_cars = int(scene.cars.size());
  const SequenceLayout layout(info.folder, info.name);
  const uint64_t seed = Mix(options.seed, uint64_t(sequence_index));
  WriteCameras(options, scene, layout);
  nlohmann::json cars_json = WriteCars(scene, layout);

  const int num_statics = int(scene.statics.size());
  std::vector<ObjectLabel> gt_labels;
  StereoDetectorModel detector(options.detector, Mix(seed, 5000));
  DisparityQuality quality;
  for (int t = 0; t < options.num_frames; ++t) {
    const StereoView view = RenderStereo(options, scene, t, seed);
    WriteImage(layout.LeftImage(t), view.left_image);
    WriteImage(layout.RightImage(t), view.right_image);
    const std::vector<int> visible = WriteGroundTruthMaps(scene, view.left_buffers, layout, t);
    const cv::Mat disparity =
        options.disparity == DisparitySource::kStereoSgbm
            ? ComputeDisparity(view.left_image, view.right_image, StereoOptions())
            : TrueDisparityWithNoise(options, view.left_buffers, num_statics, Mix(seed, uint64_t(3000 + t)));
    quality.Add(options, view.left_buffers, num_statics, disparity);
    WriteDisparity(layout.Disparity(t), disparity);
    WriteRoadPlane(options, scene, layout, t);
    WriteLabels(layout.Detections(t), DetectFrame(scene, t, camera, visible, &detector, &gt_labels, &info));
    if (progress) progress->Tick();
  }
  info.num_gt_labels = int(gt_labels.size());
  info.car_pixels = quality.car_pixels;
  info.car_disparity_mae_px = quality.valid > 0 ? quality.error_sum / double(quality.valid) : 0.0;
  info.car_disparity_valid_fraction =
      quality.car_pixels > 0 ? double(quality.valid) / double(quality.car_pixels) : 0.0;
  WriteTrackingLabels(layout.GroundTruthLabels(), gt_labels);
  WriteTextFileAtomically(layout.GroundTruthCars(), DumpJson(SceneJson(options, scene, info, cars_json), 2) + "\n");
  return info;
}

}  // namespace samp::synth
