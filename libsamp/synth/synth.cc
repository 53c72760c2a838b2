#include "libsamp/synth/synth.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/core/json_text.h"
#include "libsamp/core/log.h"
#include "libsamp/core/progress.h"
#include "libsamp/core/util.h"
#include "libsamp/data/detector_noise.h"
#include "libsamp/scan/canonical.h"
#include "libsamp/scan/mesh_io.h"
#include "libsamp/synth/scene.h"
#include "libsamp/synth/sequence_writer.h"
#include "libsamp/synth/synth_option_table.h"

namespace samp {

namespace fs = std::filesystem;
using synth::MotionType;
using synth::PlanarState;
using synth::SceneCar;

void SynthCarSource::Check() const {
  SAMP_CHECK(!cad_folder.empty() || !canonical_meshes.empty())
      << "synth: give a CAD folder or canonical meshes (cad_folder and canonical_meshes are both empty)";
  SAMP_CHECK(manifest_path.empty() || !cad_folder.empty())
      << "synth: manifest_path needs cad_folder";
}

std::vector<SynthCar> LoadSynthCars(const SynthCarSource& source) {
  source.Check();
  std::vector<SynthCar> cars;
  std::set<std::string> wanted;
  for (const std::string& name : source.only) wanted.insert(Lower(name));
  std::set<std::string> found;
  if (!source.cad_folder.empty()) {
    SAMP_CHECK(fs::is_directory(source.cad_folder)) << "synth: CAD folder " << source.cad_folder
                                                    << " does not exist";
    Manifest manifest;
    if (!source.manifest_path.empty()) manifest = LoadManifest(source.manifest_path);
    std::vector<CadFile> files = ListCadFiles(source.cad_folder, &manifest);
    std::sort(files.begin(), files.end(), [](const CadFile& a, const CadFile& b) {
      return fs::path(a.path) < fs::path(b.path);  // the order of fs::path
    });
    for (const CadFile& file : files) {
      const std::string& relative = file.relative_path;
      const ManifestEntry* entry = file.entry;
      const std::string& name = file.name;
      const std::string stem = fs::path(file.path).stem().string();
      const bool selected = wanted.empty() || wanted.count(Lower(name)) || wanted.count(Lower(stem));
      if (!selected) continue;
      if (entry && entry->skip && !(source.ignore_skip_for_only && !wanted.empty())) {
        LogDebug() << "synth: skipping " << relative << " (manifest: " << entry->skip_reason << ")";
        continue;
      }
      const Mesh cad_mesh = LoadMesh(file.path);
      const CanonicalizeResult result = Canonicalize(cad_mesh, file.canonicalize);
      for (const std::string& warning : result.warnings) {
        LogWarning() << "synth: " << relative << ": " << warning;
      }
      // Canonicalize appends the synthesised tyres after the body's triangles.
      cars.push_back({name, result.mesh, result.wheels_added ? int(cad_mesh.triangles.size()) : -1});
      if (result.wheels_added) LogDebug() << "synth: " << name << ": " << result.wheels.BriefReport();
      found.insert(Lower(name));
      found.insert(Lower(stem));
    }
  }
  for (const std::string& path : source.canonical_meshes) {
    SynthCar car{fs::path(path).stem().string(), LoadMesh(path)};
    const Eigen::Vector3d size = car.mesh.Bounds().Size();
    SAMP_CHECK(size.x() > 1.0 && size.x() < 10.0 && size.y() > 0.5 && size.z() > 0.5)
        << "synth: " << path << " does not look like a canonical car (extent " << size.transpose()
        << " m; expected x = length, y = height, z = width in metres)";
    found.insert(Lower(car.name));
    cars.push_back(std::move(car));
  }
  for (const std::string& name : wanted) {
    SAMP_CHECK(found.count(name)) << "synth: car '" << name << "' was not found in "
                                  << source.cad_folder;
  }
  SAMP_CHECK(!cars.empty()) << "synth: no car to use (all skipped or none found)";
  std::sort(cars.begin(), cars.end(), [](const SynthCar& a, const SynthCar& b) { return a.name < b.name; });
  return cars;
}

SynthOptions SynthOptions::Clean() {
  SynthOptions o;
  o.scene = SynthScene::kClean;
  o.parked_cars_per_sequence = 0;
  o.max_ego_speed = 8.0;
  o.max_ego_yaw_rate = 0.04;
  o.ego_pitch_sway_deg = o.ego_roll_sway_deg = o.ego_bounce = o.ego_max_pitch_offset_deg = 0.0;
  o.image_noise_sigma = 2.0;  // the street default is 0.7
  // 3DOP-like detections: white noise, no false positives.
  DetectorModelOptions& d = o.detector;
  d.ray_sigma_a = 0.1;
  d.ray_sigma_b = 0.0;
  d.ray_sigma_c = 0.001;
  d.lateral_sigma_a = 0.05;
  d.lateral_sigma_b = 0.005;
  d.vertical_sigma = 0.05;
  d.size_sigma = 0.0;
  d.relative_size_sigma = 0.05;
  d.yaw_sigma_deg_a = 3.0;
  d.yaw_sigma_deg_b = 0.15;
  d.flip_probability = 0.08;
  d.flip_mean_run_frames = 0.0;
  d.miss_probability = 0.05;
  d.miss_mean_run_frames = 0.0;
  d.correlation_frames = 0.0;
  d.false_positives_per_frame = 0.0;
  return o;
}

void SynthOptions::Check() const {
  SAMP_CHECK(!output_folder.empty()) << "synth: output_folder is empty";
  SynthOptionTable().Check(*this);
}

std::string SynthOptions::ToJson() const {
  nlohmann::json j = nlohmann::json::object();
  OptionsJson io(&j);
  SynthOptions copy = *this;  // the writer only reads the fields
  SynthOptionTable().Json(io, copy);
  return DumpJson(j, 2);
}

std::string SynthSummary::BriefReport() const {
  std::ostringstream out;
  out << "synth: " << sequences.size() << " sequences, " << num_tracks << " tracks (" << num_standing
      << " standing of which " << num_parked << " parked, " << num_straight << " straight, " << num_turning
      << " turning)";
  int detections = 0, labels = 0, false_positives = 0;
  for (const SynthSequenceInfo& s : sequences) {
    detections += s.num_detections;
    labels += s.num_gt_labels;
    false_positives += s.num_false_positives;
  }
  char disparity[160];
  std::snprintf(disparity, sizeof(disparity),
                "; disparity on car pixels: mean abs. error %.2f px, %.1f %% valid", car_disparity_mae_px,
                100.0 * car_disparity_valid_fraction);
  out << ", " << labels << " visible car-frames, " << detections << " detections (" << false_positives
      << " false positives)" << disparity << ", " << Progress::FormatDuration(seconds);
  return out.str();
}

std::vector<Eigen::Vector4d> SynthTrajectory(const Eigen::Vector4d& origin_pose, double speed, double yaw_rate,
                                             int num_frames, int origin_frame, double frame_rate_hz) {
  SAMP_CHECK(num_frames >= 1 && frame_rate_hz > 0) << "SynthTrajectory: num_frames " << num_frames
                                                   << ", frame_rate_hz " << frame_rate_hz;
  PlanarState origin;
  origin.position = origin_pose.head<3>();
  origin.heading = origin_pose[3];
  const double dt = 1.0 / frame_rate_hz;
  std::vector<Eigen::Vector4d> poses;
  for (int t = 0; t < num_frames; ++t) {
    const PlanarState s = synth::Advance(origin, speed, yaw_rate, (t - origin_frame) * dt);
    poses.emplace_back(s.position.x(), s.position.y(), s.position.z(), WrapAngle(s.heading));
  }
  return poses;
}

std::string SynthDetectorModelPath(const SequenceLayout& layout) {
  return (fs::path(layout.GroundTruthFolder()) / "detector_model.json").string();
}

SynthSummary SynthesizeSequences(const SynthOptions& options, const std::vector<SynthCar>& cars) {
  options.Check();
  SAMP_CHECK(!cars.empty()) << "synth: no cars given";
  for (const SynthCar& car : cars) {
    SAMP_CHECK(!car.mesh.Empty()) << "synth: car " << car.name << " has an empty mesh";
  }
  const auto start = std::chrono::steady_clock::now();
  LogInfo() << "synth: seed " << options.seed << ", " << options.num_sequences << " sequences of "
            << options.num_frames << " frames, " << cars.size() << " cars available, disparity "
            << (options.disparity == DisparitySource::kStereoSgbm ? "StereoSGBM" : "true + noise");
  nlohmann::json config = nlohmann::json::parse(options.ToJson());
  nlohmann::json names = nlohmann::json::array();
  for (const SynthCar& car : cars) names.push_back(car.name);
  config["cars"] = names;
  WriteTextFileAtomically((fs::path(options.output_folder) / "config.json").string(), DumpJson(config, 2) + "\n");

  const DetectorNoiseModel true_model =
      TrueDetectorNoiseModel(options.detector, options.min_distance, options.max_distance);
  SynthSummary summary;
  Progress progress("synth frames", int64_t(options.num_sequences) * options.num_frames,
                    options.show_progress);
  int global_car_index = 0;
  for (int i = 0; i < options.num_sequences; ++i) {
    const synth::Scene scene = synth::MakeScene(options, cars, i, &global_car_index);
    summary.sequences.push_back(synth::WriteSequence(options, scene, i, &progress));
    // The detector's true noise model beside the ground truth (`samp fit --detector-model`).
    const SequenceLayout layout(summary.sequences.back().folder, summary.sequences.back().name);
    WriteDetectorNoiseModel(SynthDetectorModelPath(layout), true_model);
    for (const SceneCar& car : scene.cars) {
      ++summary.num_tracks;
      if (car.motion == MotionType::kStanding) ++summary.num_standing;
      if (car.motion == MotionType::kStraight) ++summary.num_straight;
      if (car.motion == MotionType::kTurning) ++summary.num_turning;
      if (car.parked) ++summary.num_parked;
    }
  }
  progress.Finish();
  double error_sum = 0.0, valid = 0.0, pixels = 0.0;
  for (const SynthSequenceInfo& s : summary.sequences) {
    const double v = s.car_disparity_valid_fraction * double(s.car_pixels);
    error_sum += s.car_disparity_mae_px * v;
    valid += v;
    pixels += double(s.car_pixels);
  }
  summary.car_disparity_mae_px = valid > 0 ? error_sum / valid : 0.0;
  summary.car_disparity_valid_fraction = pixels > 0 ? valid / pixels : 0.0;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace samp
