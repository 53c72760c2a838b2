#include "tests/viz/fit_run_fixture.h"

#include <cmath>
#include <filesystem>
#include <random>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/mesh.h"
#include "libsamp/core/ply_io.h"
#include "libsamp/core/camera.h"
#include "libsamp/pipeline/fit_config.h"
#include "libsamp/pipeline/fit_output.h"
#include "libsamp/viz/fit_run.h"
#include "libsamp/viz/image.h"
#include "libsamp/viz/inspect.h"

namespace samp::testing {

namespace fs = std::filesystem;

namespace {

std::string Frame(const std::string& name, int frame, const std::string& extension) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "_%02d", frame);
  return name + buffer + extension;
}

// A KITTI label (docs/sequence_format.md): camera frame of its frame.
struct ObjectLabel {
  int frame = -1, track_id = -1;
  double alpha = 0, height = 0, width = 0, length = 0, rotation_y = 0;
  Eigen::Vector4d box_2d = Eigen::Vector4d::Zero();
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

std::string Line(const ObjectLabel& l) {
  char buffer[512];
  std::snprintf(buffer, sizeof(buffer), "Car 0 0 %.4f %.2f %.2f %.2f %.2f %.4f %.4f %.4f %.4f %.4f %.4f %.4f 1",
                l.alpha, l.box_2d[0], l.box_2d[1], l.box_2d[2], l.box_2d[3], l.height, l.width, l.length,
                l.position.x(), l.position.y(), l.position.z(), l.rotation_y);
  return buffer;
}

void WriteLabels(const std::string& path, const std::vector<ObjectLabel>& labels) {
  std::string text;
  for (const ObjectLabel& l : labels) text += Line(l) + "\n";
  WriteTextFileAtomically(path, text);
}

void WriteTrackingLabels(const std::string& path, const std::vector<ObjectLabel>& labels) {
  std::string text;
  for (const ObjectLabel& l : labels) text += std::to_string(l.frame) + " " + std::to_string(l.track_id) + " " + Line(l) + "\n";
  WriteTextFileAtomically(path, text);
}

// KITTI label of a box car (bottom centre at the object origin) seen from `camera_from_object`.
ObjectLabel LabelOf(const Eigen::Isometry3d& camera_from_object, const Eigen::Vector3d& lhw,
                    const PinholeCamera& camera, int frame, int track_id) {
  ObjectLabel label;
  label.frame = frame;
  label.track_id = track_id;
  label.position = camera_from_object.translation();
  const Eigen::Vector3d heading = camera_from_object.linear() * Eigen::Vector3d::UnitX();
  label.rotation_y = std::atan2(-heading.z(), heading.x());
  label.alpha = label.rotation_y - std::atan2(label.position.x(), label.position.z());
  label.length = lhw.x(), label.height = lhw.y(), label.width = lhw.z();
  double x1 = 1e30, y1 = 1e30, x2 = -1e30, y2 = -1e30;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner((c & 1) ? 0.5 * lhw.x() : -0.5 * lhw.x(), (c & 2) ? 0.0 : -lhw.y(),
                                 (c & 4) ? 0.5 * lhw.z() : -0.5 * lhw.z());
    const Eigen::Vector2d uv = camera.Project(camera_from_object * corner);
    x1 = std::min(x1, uv.x()), y1 = std::min(y1, uv.y()), x2 = std::max(x2, uv.x()), y2 = std::max(y2, uv.y());
  }
  label.box_2d << std::clamp(x1, 0.0, camera.width - 1.0), std::clamp(y1, 0.0, camera.height - 1.0),
      std::clamp(x2, 0.0, camera.width - 1.0), std::clamp(y2, 0.0, camera.height - 1.0);
  return label;
}

}  // namespace

FitRunFixture WriteFitRunFixture(const std::string& root, const FixtureOptions& options) {
  FitRunFixture fixture;
  fixture.sequence_dir = (fs::path(root) / "seq").string();
  fixture.output_dir = (fs::path(root) / "out").string();
  const std::string& name = fixture.sequence_name;
  const fs::path seq(fixture.sequence_dir), out(fixture.output_dir);
  std::mt19937 rng(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);

  PinholeCamera camera;
  camera.width = options.image_width;
  camera.height = options.image_height;
  camera.cx = options.image_width / 2.0;
  camera.cy = options.image_height * 0.46;
  {
    char p2[256], p3[256];
    std::snprintf(p2, sizeof(p2), "P2: %.6f 0 %.6f 0 0 %.6f %.6f 0 0 0 1 0\n", camera.fx, camera.cx, camera.fy, camera.cy);
    std::snprintf(p3, sizeof(p3), "P3: %.6f 0 %.6f %.6f 0 %.6f %.6f 0 0 0 1 0\n", camera.fx, camera.cx, -0.54 * camera.fx,
                  camera.fy, camera.cy);
    WriteTextFileAtomically((seq / "calib" / (name + ".txt")).string(), std::string(p2) + p3);
  }
  // The ego car drives 0.3 m per frame along z.
  std::vector<Eigen::Isometry3d> ego;
  for (int k = 0; k < options.num_frames; ++k) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(0, 0, 0.3 * k);
    ego.push_back(pose);
  }
  {
    std::string text;
    for (const Eigen::Isometry3d& pose : ego) {
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) text += std::to_string(pose.matrix()(r, c)) + (r == 2 && c == 3 ? "\n" : " ");
    }
    WriteTextFileAtomically((seq / "poses" / (name + ".txt")).string(), text);
  }
  // Images: a sky and a road.
  RgbImage image(options.image_width, options.image_height, Rgb{200, 215, 235});
  DrawRectangle(&image, 0, int(camera.cy), options.image_width - 1, options.image_height - 1, Rgb{110, 110, 115});
  for (int k = 0; k < options.num_frames; ++k) WritePng((seq / "image_2" / Frame(name, k, ".png")).string(), image);

  const Eigen::Vector3d lhw(4.0, 1.5, 1.8);
  const Mesh car = MakeBoxMesh(Eigen::Vector3d(-2.0, -1.5, -0.9), Eigen::Vector3d(2.0, 0.0, 0.9));
  const double m = fixture.gt_margin;
  const Mesh true_car = MakeBoxMesh(Eigen::Vector3d(-2.0 - m, -1.5 - m, -0.9 - m), Eigen::Vector3d(2.0 + m, m, 0.9 + m));
  const std::vector<Eigen::Vector3f> surface = SampleSurface(car, options.points_per_frame, options.seed);

  std::vector<std::vector<ObjectLabel>> detections(options.num_frames);
  std::vector<ObjectLabel> gt_labels;
  TracksFileSequence sequence;
  const double road_y = 1.65;
  for (int t = 0; t < options.num_tracks; ++t) {
    FixtureTrack track;
    track.id = 3 * t + 1;
    const double lateral = (t % 2 == 0 ? -1.0 : 1.0) * (3.0 + 2.5 * (t / 2));
    const double start = 12.0 + 7.0 * t, speed = (t == 0) ? 0.0 : 4.0 + 2.0 * t;
    const double yaw = -M_PI / 2 + 0.05 * t;  // heading along +z
    TracksFileTrack record;
    PointCloud aligned;
    for (int k = 0; k < options.num_frames; ++k) {
      const double time = k / 10.0;
      const Eigen::Vector3d heading(std::cos(yaw), 0, -std::sin(yaw));
      const Eigen::Isometry3d truth = PoseFromYaw(Eigen::Vector3d(lateral, road_y, start) + speed * time * heading, yaw);
      const double fitted_yaw = yaw + 0.01 * normal(rng);
      const Eigen::Isometry3d fitted =
          PoseFromYaw(truth.translation() + 0.03 * Eigen::Vector3d(normal(rng), 0, normal(rng)), fitted_yaw);
      const Eigen::Isometry3d detected =
          PoseFromYaw(truth.translation() + Eigen::Vector3d(0.15 * normal(rng), 0, 0.5 * normal(rng)), yaw + 0.15 * normal(rng));
      track.true_world_from_object.push_back(truth);
      track.fitted_world_from_object.push_back(fitted);
      const Eigen::Isometry3d camera_from_world = ego[k].inverse();
      detections[k].push_back(LabelOf(camera_from_world * detected, lhw, camera, -1, -1));
      ObjectLabel gt = LabelOf(camera_from_world * truth, lhw + 2 * m * Eigen::Vector3d::Ones(), camera, k, track.id);
      gt_labels.push_back(gt);
      // Points on the true surface, in the world; written in the fitted object frame.
      std::vector<Eigen::Vector3f> world;
      const double a = options.num_frames > 1 ? double(k) / (options.num_frames - 1) : 0.0;
      const Eigen::Matrix<uint8_t, 3, 1> color(uint8_t(255 * a), 64, uint8_t(255 * (1 - a)));
      for (const Eigen::Vector3f& p : surface) {
        const Eigen::Vector3d w = truth * (p.cast<double>() + 0.02 * Eigen::Vector3d(normal(rng), normal(rng), normal(rng)));
        world.push_back(w.cast<float>());
        aligned.points.push_back((fitted.inverse() * w).cast<float>());
        aligned.colors.push_back(color);
      }
      track.points_in_world.push_back(world);
      FrameFit frame;
      frame.frame = k;
      frame.time = time;
      frame.position = fitted.translation();
      frame.yaw = fitted_yaw;
      frame.speed = speed;
      frame.yaw_rate = 0.0;
      frame.motion_model = speed < 1.0 ? "standing" : "straight";
      frame.num_points = options.points_per_frame;
      frame.effective_points = options.points_per_frame;
      frame.data_cost = 0.01 * (k + 1);
      record.fit.frames.push_back(frame);
    }
    const std::string mesh = "meshes/track_" + std::to_string(track.id) + ".ply";
    const std::string points = "meshes/track_" + std::to_string(track.id) + "_points.ply";
    WritePly((out / mesh).string(), car);
    WritePly((out / points).string(), aligned);
    if (options.ground_truth) {
      WritePly((seq / "gt" / "meshes" / ("track_" + std::to_string(track.id) + ".ply")).string(), true_car);
    }
    record.fit.track_id = track.id;
    record.fit.sequence = name;
    record.fit.type = "Car";
    record.fit.single_frame = false;
    record.fit.shape_code = Eigen::Vector3d(0.5 - 0.2 * t, 0.1 * t, -0.3);
    record.box.min = Eigen::Vector3d(-2.0, -1.5, -0.9);
    record.box.max = Eigen::Vector3d(2.0, 0.0, 0.9);
    record.fit.summary.initial_cost = 1.5 + t;
    record.fit.summary.final_cost = 0.2 + 0.01 * t;
    record.fit.summary.num_iterations = 12;
    record.fit.summary.seconds = 0.05;
    record.fit.summary.usable = true;
    record.mesh = mesh;
    record.points = points;
    sequence.tracks.push_back(std::move(record));
    fixture.tracks.push_back(std::move(track));
  }
  for (int k = 0; k < options.num_frames; ++k) {
    WriteLabels((seq / "detections" / Frame(name, k, ".txt")).string(), detections[k]);
  }
  if (options.ground_truth) WriteTrackingLabels((seq / "gt" / "label_02" / (name + ".txt")).string(), gt_labels);
  sequence.directory = fixture.sequence_dir;
  sequence.name = name;
  sequence.ok = true;
  sequence.input = "fixture";
  sequence.tracking = nlohmann::json::object();
  TracksFile tracks_file;
  tracks_file.model = (out / "no_model.vdb").string();
  tracks_file.sequences.push_back(std::move(sequence));
  WriteTracksFile((out / "tracks.json").string(), tracks_file);
  FitConfig config;
  config.options.model_path = tracks_file.model;
  config.options.sequences = {fixture.sequence_dir};
  config.options.output_dir = fixture.output_dir;
  WriteFitConfig((out / "config.json").string(), config);
  return fixture;
}

}  // namespace samp::testing
