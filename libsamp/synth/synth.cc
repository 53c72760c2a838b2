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
  SAMP_CHECK(num_sequences >= 1) << "synth: num_sequences must be >= 1";
  SAMP_CHECK(first_sequence >= 0 && first_sequence + num_sequences <= 1000000)
      << "synth: first_sequence must be in [0, 999999 - num_sequences]";
  SAMP_CHECK(cars_per_sequence >= 1 && cars_per_sequence <= 20) << "synth: cars_per_sequence must be in [1, 20]";
  SAMP_CHECK(num_frames >= 1 && num_frames <= 100) << "synth: num_frames must be in [1, 100]";
  SAMP_CHECK(layout == SynthLayout::kSamp || first_sequence + num_sequences <= 10000)
      << "synth: the KITTI tracking layout names sequences with 4 digits: first_sequence + num_sequences "
         "must be <= 10000";
  SAMP_CHECK(frame_rate_hz > 0) << "synth: frame_rate_hz must be > 0";
  SAMP_CHECK(width >= 32 && height >= 32) << "synth: image size must be at least 32 x 32";
  SAMP_CHECK(focal_px > 0 && baseline > 0) << "synth: focal_px and baseline must be > 0";
  SAMP_CHECK(cx_px > 0 && cx_px < width && cy_px > 0 && cy_px < height)
      << "synth: the principal point must lie inside the image";
  SAMP_CHECK(camera_height > 0.5) << "synth: camera_height must be > 0.5 m";
  SAMP_CHECK(min_distance >= 4.0 && max_distance > min_distance && max_distance <= 150.0)
      << "synth: need 4 <= min_distance < max_distance <= 150";
  SAMP_CHECK(min_speed > 0 && max_speed >= min_speed) << "synth: need 0 < min_speed <= max_speed";
  SAMP_CHECK(min_turn_speed > 0 && max_turn_speed >= min_turn_speed)
      << "synth: need 0 < min_turn_speed <= max_turn_speed";
  SAMP_CHECK(min_yaw_rate > 0 && max_yaw_rate >= min_yaw_rate)
      << "synth: need 0 < min_yaw_rate <= max_yaw_rate";
  SAMP_CHECK(min_ego_speed >= 0 && max_ego_speed >= min_ego_speed)
      << "synth: need 0 <= min_ego_speed <= max_ego_speed";
  SAMP_CHECK(max_ego_yaw_rate >= 0) << "synth: max_ego_yaw_rate must be >= 0";
  SAMP_CHECK(image_noise_sigma >= 0) << "synth: image_noise_sigma must be >= 0";
  SAMP_CHECK(disparity_sigma_px >= 0 && car_disparity_sigma_px >= 0)
      << "synth: disparity noise must be >= 0";
  SAMP_CHECK(invalid_fraction >= 0 && outlier_fraction >= 0 && invalid_fraction + outlier_fraction <= 1)
      << "synth: invalid_fraction and outlier_fraction must be >= 0 with sum <= 1";
  SAMP_CHECK(parked_cars_per_sequence >= 0 && parked_cars_per_sequence <= 12)
      << "synth: parked_cars_per_sequence must be in [0, 12]";
  SAMP_CHECK(near_share >= 0 && near_share <= 1) << "synth: near_share must lie in [0, 1]";
  SAMP_CHECK(standing_share >= 0 && turning_share >= 0 && standing_share + turning_share <= 1)
      << "synth: standing_share and turning_share must be >= 0 with sum <= 1";
  SAMP_CHECK(ego_pitch_sway_deg >= 0 && ego_roll_sway_deg >= 0 && ego_bounce >= 0 && ego_max_pitch_offset_deg >= 0)
      << "synth: ego sway amplitudes must be >= 0";
  SAMP_CHECK(min_sun_elevation_deg > 0 && max_sun_elevation_deg >= min_sun_elevation_deg &&
             max_sun_elevation_deg <= 90)
      << "synth: need 0 < min_sun_elevation_deg <= max_sun_elevation_deg <= 90";
  SAMP_CHECK(paint_specular >= 0 && paint_shininess >= 1 && paint_fresnel_f0 >= 0 && paint_fresnel_f0 < 1 &&
             glass_fresnel_f0 >= 0 && glass_fresnel_f0 < 1 && paint_texture >= 0 && window_interior_albedo >= 0 &&
             window_interior_albedo <= 0.5)
      << "synth: need paint_specular >= 0, paint_shininess >= 1, 0 <= paint/glass F0 < 1, paint_texture >= 0, "
         "0 <= window_interior_albedo <= 0.5";
  street.Check();
  detector.Check();
}

std::string SynthOptions::ToJson() const {
  nlohmann::json j = {
      {"seed", seed},
      {"num_sequences", num_sequences},
      {"first_sequence", first_sequence},
      {"cars_per_sequence", cars_per_sequence},
      {"num_frames", num_frames},
      {"frame_rate_hz", frame_rate_hz},
      {"width", width},
      {"height", height},
      {"focal_px", focal_px},
      {"cx_px", cx_px},
      {"cy_px", cy_px},
      {"baseline", baseline},
      {"camera_height", camera_height},
      {"min_distance", min_distance},
      {"max_distance", max_distance},
      {"min_speed", min_speed},
      {"max_speed", max_speed},
      {"min_turn_speed", min_turn_speed},
      {"max_turn_speed", max_turn_speed},
      {"min_yaw_rate", min_yaw_rate},
      {"max_yaw_rate", max_yaw_rate},
      {"min_ego_speed", min_ego_speed},
      {"max_ego_speed", max_ego_speed},
      {"max_ego_yaw_rate", max_ego_yaw_rate},
      {"image_noise_sigma", image_noise_sigma},
      {"disparity", disparity == DisparitySource::kStereoSgbm ? "sgbm" : "true+noise"},
      {"disparity_sigma_px", disparity_sigma_px},
      {"car_disparity_sigma_px", car_disparity_sigma_px},
      {"invalid_fraction", invalid_fraction},
      {"outlier_fraction", outlier_fraction},
      {"scene", scene == SynthScene::kStreet ? "street" : "clean"},
      {"parked_cars_per_sequence", parked_cars_per_sequence},
      {"near_share", near_share},
      {"standing_share", standing_share},
      {"turning_share", turning_share},
      {"ego_pitch_sway_deg", ego_pitch_sway_deg},
      {"ego_roll_sway_deg", ego_roll_sway_deg},
      {"ego_bounce", ego_bounce},
      {"ego_max_pitch_offset_deg", ego_max_pitch_offset_deg},
      {"min_sun_elevation_deg", min_sun_elevation_deg},
      {"max_sun_elevation_deg", max_sun_elevation_deg},
      {"paint_specular", paint_specular},
      {"paint_shininess", paint_shininess},
      {"paint_fresnel_f0", paint_fresnel_f0},
      {"glass_fresnel_f0", glass_fresnel_f0},
      {"paint_texture", paint_texture},
      {"window_interior_albedo", window_interior_albedo},
      {"shadows", shadows},
      {"street",
       {{"two_lane_probability", street.two_lane_probability},
        {"min_lane_width", street.min_lane_width},
        {"max_lane_width", street.max_lane_width},
        {"right_parking_probability", street.right_parking_probability},
        {"left_parking_probability", street.left_parking_probability},
        {"kerb_height", street.kerb_height},
        {"min_sidewalk_width", street.min_sidewalk_width},
        {"max_sidewalk_width", street.max_sidewalk_width},
        {"min_facade_distance", street.min_facade_distance},
        {"max_facade_distance", street.max_facade_distance},
        {"clutter_spacing", street.clutter_spacing},
        {"intersection_probability", street.intersection_probability},
        {"min_parked_gap", street.min_parked_gap},
        {"max_parked_gap", street.max_parked_gap}}},
      {"detector",
       {{"ray_sigma_a", detector.ray_sigma_a},
        {"ray_sigma_b", detector.ray_sigma_b},
        {"ray_sigma_c", detector.ray_sigma_c},
        {"lateral_sigma_a", detector.lateral_sigma_a},
        {"lateral_sigma_b", detector.lateral_sigma_b},
        {"vertical_sigma", detector.vertical_sigma},
        {"size_sigma", detector.size_sigma},
        {"relative_size_sigma", detector.relative_size_sigma},
        {"yaw_sigma_deg_a", detector.yaw_sigma_deg_a},
        {"yaw_sigma_deg_b", detector.yaw_sigma_deg_b},
        {"flip_probability", detector.flip_probability},
        {"flip_mean_run_frames", detector.flip_mean_run_frames},
        {"miss_probability", detector.miss_probability},
        {"miss_mean_run_frames", detector.miss_mean_run_frames},
        {"correlation_frames", detector.correlation_frames},
        {"false_positives_per_frame", detector.false_positives_per_frame},
        {"false_positive_mean_run_frames", detector.false_positive_mean_run_frames},
        {"box_sigma_px", detector.box_sigma_px},
        {"min_pixels", detector.min_pixels}}}};
  if (layout == SynthLayout::kKittiTracking) j["layout"] = "kitti-tracking";  // samp's: not written
  // Written only when set, so that the files of the preset's own detector stay as they were.
  nlohmann::json& d = j["detector"];
  if (!detector.profile.empty()) d["profile"] = detector.profile;
  if (detector.height_bias != 0.0) d["height_bias"] = detector.height_bias;
  if (detector.width_bias != 0.0) d["width_bias"] = detector.width_bias;
  if (detector.length_bias != 0.0) d["length_bias"] = detector.length_bias;
  if (detector.along_ray_bias != 0.0) d["along_ray_bias"] = detector.along_ray_bias;
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
