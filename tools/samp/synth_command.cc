// `samp synth`: CAD cars -> synthetic KITTI-like stereo sequences with ground truth.
#include <functional>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "libsamp/core/log.h"
#include "libsamp/synth/synth.h"
#include "tools/samp/commands.h"

namespace samp::tools {
namespace {

// Every scene option is registered through this table, so that `--preset`
// can supply other defaults while the options given on the command line win.
class SynthOptionTable {
 public:
  SynthOptionTable(CLI::App* command, SynthOptions* parsed) : command_(command), parsed_(parsed) {}

  template <typename T>
  CLI::Option* Add(const std::string& flags, std::function<T&(SynthOptions&)> field, const std::string& help) {
    CLI::Option* option = command_->add_option(flags, field(*parsed_), help)->capture_default_str();
    entries_.push_back({option, [field](SynthOptions& to, SynthOptions& from) { field(to) = field(from); }});
    return option;
  }

  // The preset's options with every option given on the command line copied over.
  SynthOptions Apply(SynthOptions preset) const {
    for (const Entry& entry : entries_) {
      if (entry.option->count() > 0) entry.copy(preset, *parsed_);
    }
    return preset;
  }

 private:
  struct Entry {
    CLI::Option* option;
    std::function<void(SynthOptions&, SynthOptions&)> copy;
  };
  CLI::App* command_;
  SynthOptions* parsed_;
  std::vector<Entry> entries_;
};

}  // namespace

void RegisterSynthCommand(CLI::App* app) {
  struct Args {
    SynthOptions options;
    SynthCarSource cars;
    std::string disparity = "sgbm";
    std::string preset = "street";
    std::string layout = "samp";
    std::string detector_profile;
    bool no_shadows = false;
    std::unique_ptr<SynthOptionTable> table;
  };
  auto args = std::make_shared<Args>();
  SynthCarSource& c = args->cars;
  CLI::App* command = app->add_subcommand(
      "synth",
      "Synthesize KITTI-like stereo sequences of CAD cars with ground truth (docs/synthetic.md).\n"
      "Default: realistic streets (lanes, kerbs, facades, clutter, parked rows, traffic, paint with\n"
      "reflections, shadows, ego sway) and a stereo 3D detector's errors; --preset clean gives the\n"
      "first benchmark's clean scenes. Writes OUT/<seq>/ in the layout `samp fit` reads (calib,\n"
      "image_2, image_3, disparity, detections, planes, poses) plus OUT/<seq>/gt/ (label_02, depth,\n"
      "obj_map, meshes, cars.json). Same options and seed give the same files.");
  args->table = std::make_unique<SynthOptionTable>(command, &args->options);
  SynthOptionTable& t = *args->table;
  using O = SynthOptions;
  command->add_option("-o,--out", args->options.output_folder, "Output folder (one sub-folder per sequence)")
      ->required();
  command->add_option("--preset", args->preset,
                      "Scene preset: 'street' (realistic, the default) or 'clean' (the first benchmark's "
                      "scenes: plain paint, no clutter, white detection noise); options given explicitly "
                      "override the preset")
      ->capture_default_str()
      ->check(CLI::IsMember({"street", "clean"}));
  command->add_option("--cad", c.cad_folder, "Folder searched recursively for CAD car files")
      ->check(CLI::ExistingDirectory);
  command->add_option("--manifest", c.manifest_path,
                      "Training manifest (JSON) for canonicalisation (docs/canonical_frame.md)")
      ->check(CLI::ExistingFile);
  command->add_option("--car", c.only,
                      "Use only this car (manifest name or file stem); repeatable. Cars marked skip "
                      "in the manifest are used when named here (held-out evaluation cars)");
  command->add_option("--car-mesh", c.canonical_meshes,
                      "A mesh already in the canonical object frame (origin bottom centre, x front, "
                      "y down, z left, metres); repeatable")
      ->check(CLI::ExistingFile);

  // Sequences and camera.
  t.Add<uint64_t>("--seed", [](O& o) -> uint64_t& { return o.seed; }, "Seed of all random choices");
  t.Add<int>("--sequences", [](O& o) -> int& { return o.num_sequences; }, "Number of sequences")
      ->check(CLI::PositiveNumber);
  t.Add<int>("--first-sequence", [](O& o) -> int& { return o.first_sequence; },
             "Number of the first sequence (<seq> = %06d)")
      ->check(CLI::NonNegativeNumber);
  t.Add<int>("--cars-per-sequence", [](O& o) -> int& { return o.cars_per_sequence; },
             "Traffic cars per sequence (moving or waiting)")
      ->check(CLI::Range(1, 20));
  t.Add<int>("--parked-cars", [](O& o) -> int& { return o.parked_cars_per_sequence; },
             "Street: parked cars per sequence, in rows in the parking lanes")
      ->check(CLI::Range(0, 12));
  t.Add<double>("--standing-share", [](O& o) -> double& { return o.standing_share; },
                "Street: share of the traffic cars that stand (waiting)");
  t.Add<double>("--turning-share", [](O& o) -> double& { return o.turning_share; },
                "Street: share of the traffic cars that turn (the rest drive straight)");
  t.Add<int>("--frames", [](O& o) -> int& { return o.num_frames; }, "Frames per sequence")
      ->check(CLI::Range(1, 100));
  t.Add<double>("--fps", [](O& o) -> double& { return o.frame_rate_hz; }, "Frame rate, Hz")
      ->check(CLI::PositiveNumber);
  t.Add<int>("--width", [](O& o) -> int& { return o.width; }, "Image width, px");
  t.Add<int>("--height", [](O& o) -> int& { return o.height; }, "Image height, px");
  t.Add<double>("--focal", [](O& o) -> double& { return o.focal_px; }, "Focal length, px");
  t.Add<double>("--cx", [](O& o) -> double& { return o.cx_px; }, "Principal point x, px");
  t.Add<double>("--cy", [](O& o) -> double& { return o.cy_px; }, "Principal point y, px");
  t.Add<double>("--baseline", [](O& o) -> double& { return o.baseline; }, "Stereo baseline, m");
  t.Add<double>("--camera-height", [](O& o) -> double& { return o.camera_height; },
                "Camera height above the road, m");
  // Cars and motion.
  t.Add<double>("--min-distance", [](O& o) -> double& { return o.min_distance; },
                "Closest car distance at the middle frame, m");
  t.Add<double>("--max-distance", [](O& o) -> double& { return o.max_distance; },
                "Farthest car distance at the middle frame, m");
  t.Add<double>("--near-share", [](O& o) -> double& { return o.near_share; },
                "Street: share of each sequence's cars (parked and traffic) nearer than 20 m at the middle frame; "
                "parked rows and traffic cars are drawn near while the sequence is short of it (a target: placements "
                "that find no room fall back to any distance)");
  t.Add<double>("--min-speed", [](O& o) -> double& { return o.min_speed; }, "Straight cars: minimal speed, m/s");
  t.Add<double>("--max-speed", [](O& o) -> double& { return o.max_speed; }, "Straight cars: maximal speed, m/s");
  t.Add<double>("--min-turn-speed", [](O& o) -> double& { return o.min_turn_speed; },
                "Turning cars: minimal speed, m/s");
  t.Add<double>("--max-turn-speed", [](O& o) -> double& { return o.max_turn_speed; },
                "Turning cars: maximal speed, m/s");
  t.Add<double>("--min-yaw-rate", [](O& o) -> double& { return o.min_yaw_rate; },
                "Turning cars: minimal absolute yaw rate, rad/s");
  t.Add<double>("--max-yaw-rate", [](O& o) -> double& { return o.max_yaw_rate; },
                "Turning cars: maximal absolute yaw rate, rad/s");
  t.Add<double>("--min-ego-speed", [](O& o) -> double& { return o.min_ego_speed; }, "Minimal ego speed, m/s");
  t.Add<double>("--max-ego-speed", [](O& o) -> double& { return o.max_ego_speed; }, "Maximal ego speed, m/s");
  t.Add<double>("--max-ego-yaw-rate", [](O& o) -> double& { return o.max_ego_yaw_rate; },
                "Maximal absolute ego yaw rate, rad/s");
  t.Add<double>("--ego-pitch-sway", [](O& o) -> double& { return o.ego_pitch_sway_deg; },
                "Street: ego pitch sway amplitude at the maximal ego speed, deg");
  t.Add<double>("--ego-roll-sway", [](O& o) -> double& { return o.ego_roll_sway_deg; },
                "Street: ego roll sway amplitude at the maximal ego speed, deg");
  t.Add<double>("--ego-bounce", [](O& o) -> double& { return o.ego_bounce; },
                "Street: ego vertical bounce amplitude at the maximal ego speed, m");
  t.Add<double>("--ego-pitch-offset", [](O& o) -> double& { return o.ego_max_pitch_offset_deg; },
                "Street: maximal constant camera pitch (mounting, load), deg");
  // Street layout.
  t.Add<double>("--two-lane-probability", [](O& o) -> double& { return o.street.two_lane_probability; },
                "Street: probability of two driving lanes per direction (else one)");
  t.Add<double>("--min-lane-width", [](O& o) -> double& { return o.street.min_lane_width; },
                "Street: minimal lane width, m");
  t.Add<double>("--max-lane-width", [](O& o) -> double& { return o.street.max_lane_width; },
                "Street: maximal lane width, m");
  t.Add<double>("--right-parking-probability", [](O& o) -> double& { return o.street.right_parking_probability; },
                "Street: probability of a parking lane on the right");
  t.Add<double>("--left-parking-probability", [](O& o) -> double& { return o.street.left_parking_probability; },
                "Street: probability of a parking lane on the left");
  t.Add<double>("--kerb-height", [](O& o) -> double& { return o.street.kerb_height; }, "Street: kerb height, m");
  t.Add<double>("--min-sidewalk-width", [](O& o) -> double& { return o.street.min_sidewalk_width; },
                "Street: minimal sidewalk width, m");
  t.Add<double>("--max-sidewalk-width", [](O& o) -> double& { return o.street.max_sidewalk_width; },
                "Street: maximal sidewalk width, m");
  t.Add<double>("--min-facade-distance", [](O& o) -> double& { return o.street.min_facade_distance; },
                "Street: minimal facade distance from the kerb, m");
  t.Add<double>("--max-facade-distance", [](O& o) -> double& { return o.street.max_facade_distance; },
                "Street: maximal facade distance from the kerb, m");
  t.Add<double>("--clutter-spacing", [](O& o) -> double& { return o.street.clutter_spacing; },
                "Street: mean spacing of poles, trees, bins, signs, bollards per side, m");
  t.Add<double>("--intersection-probability", [](O& o) -> double& { return o.street.intersection_probability; },
                "Street: probability of a crossing street 15-45 m ahead");
  t.Add<double>("--min-parked-gap", [](O& o) -> double& { return o.street.min_parked_gap; },
                "Street: minimal gap between parked cars, m");
  t.Add<double>("--max-parked-gap", [](O& o) -> double& { return o.street.max_parked_gap; },
                "Street: maximal gap between parked cars, m");
  // Appearance.
  t.Add<double>("--min-sun-elevation", [](O& o) -> double& { return o.min_sun_elevation_deg; },
                "Street: minimal sun elevation, deg");
  t.Add<double>("--max-sun-elevation", [](O& o) -> double& { return o.max_sun_elevation_deg; },
                "Street: maximal sun elevation, deg");
  t.Add<double>("--paint-specular", [](O& o) -> double& { return o.paint_specular; },
                "Street: strength of the sun highlight on the paint");
  t.Add<double>("--paint-shininess", [](O& o) -> double& { return o.paint_shininess; },
                "Street: Blinn-Phong exponent of the paint's highlight");
  t.Add<double>("--paint-fresnel", [](O& o) -> double& { return o.paint_fresnel_f0; },
                "Street: Schlick F0 of the paint's sky reflection");
  t.Add<double>("--glass-fresnel", [](O& o) -> double& { return o.glass_fresnel_f0; },
                "Street: Schlick F0 of the windows' sky reflection");
  t.Add<double>("--paint-texture", [](O& o) -> double& { return o.paint_texture; },
                "Street: relative amplitude of the paint's texture (dirt, orange peel)");
  t.Add<double>("--window-interior", [](O& o) -> double& { return o.window_interior_albedo; },
                "Street: mean albedo of the car interior seen through the windows (0 = black glass)");
  command->add_flag("--no-shadows", args->no_shadows, "Street: no cast sun shadows");
  t.Add<double>("--image-noise", [](O& o) -> double& { return o.image_noise_sigma; },
                "Image noise std. dev., grey levels");
  // Stereo.
  command->add_option("--disparity", args->disparity,
                      "Disparity source: 'sgbm' (OpenCV StereoSGBM on the rendered pair) or 'true' "
                      "(true disparity + the documented noise model, fast)")
      ->capture_default_str()
      ->check(CLI::IsMember({"sgbm", "true"}));
  command->add_option("--layout", args->layout,
                      "Folders written: 'samp' (OUT/<seq>/, the default) or 'kitti-tracking' (KITTI tracking's "
                      "own: OUT/training/image_02|image_03/<seq>/, calib/, oxts/, label_02/, and the detections "
                      "OUT/detections/<seq>.txt; docs/sequence_format.md)")
      ->capture_default_str()
      ->check(CLI::IsMember({"samp", "kitti-tracking"}));
  t.Add<double>("--disparity-noise", [](O& o) -> double& { return o.disparity_sigma_px; },
                "'true' mode: disparity noise std. dev. on the background, px");
  t.Add<double>("--car-disparity-noise", [](O& o) -> double& { return o.car_disparity_sigma_px; },
                "'true' mode: disparity noise std. dev. on cars, px");
  t.Add<double>("--invalid-fraction", [](O& o) -> double& { return o.invalid_fraction; },
                "'true' mode: share of invalid pixels");
  t.Add<double>("--outlier-fraction", [](O& o) -> double& { return o.outlier_fraction; },
                "'true' mode: share of uniform outliers");
  // Detector model (docs/synthetic.md, "Detector model" and "Detector profiles").
  command
      ->add_option("--detector-profile", args->detector_profile,
                   "Detections: a named detector (replaces the preset's; --det-* options given explicitly "
                   "override its fields): default (the street preset's stereo detector), lidar (position, size "
                   "and yaw sigmas x 0.25), stereo-x2 (x 2), size-x3 (box size sigmas x 3), kitti-boxes (width "
                   "0.25 m narrower, 0.2 m nearer along the ray), flips (8 % one-frame flips)")
      ->check(CLI::IsMember(DetectorProfileNames()));
  t.Add<double>("--det-ray-sigma-a", [](O& o) -> double& { return o.detector.ray_sigma_a; },
                "Detections: position error std. dev. along the viewing ray a + b d + c d^2: a, m");
  t.Add<double>("--det-ray-sigma-b", [](O& o) -> double& { return o.detector.ray_sigma_b; },
                "Detections: ... b, m per m");
  t.Add<double>("--det-ray-sigma-c", [](O& o) -> double& { return o.detector.ray_sigma_c; },
                "Detections: ... c, 1/m");
  t.Add<double>("--det-lateral-sigma-a", [](O& o) -> double& { return o.detector.lateral_sigma_a; },
                "Detections: horizontal error std. dev. across the ray a + b d: a, m");
  t.Add<double>("--det-lateral-sigma-b", [](O& o) -> double& { return o.detector.lateral_sigma_b; },
                "Detections: ... b, m per m");
  t.Add<double>("--det-vertical-sigma", [](O& o) -> double& { return o.detector.vertical_sigma; },
                "Detections: vertical position error std. dev., m");
  t.Add<double>("--det-size-sigma", [](O& o) -> double& { return o.detector.size_sigma; },
                "Detections: std. dev. of each of h, w, l, m");
  t.Add<double>("--det-relative-size-sigma", [](O& o) -> double& { return o.detector.relative_size_sigma; },
                "Detections: relative std. dev. of each of h, w, l (added to --det-size-sigma)");
  t.Add<double>("--det-height-bias", [](O& o) -> double& { return o.detector.height_bias; },
                "Detections: systematic error of the box height, detected - true, m");
  t.Add<double>("--det-width-bias", [](O& o) -> double& { return o.detector.width_bias; },
                "Detections: systematic error of the box width, m (KITTI boxes exclude mirrors: about -0.25)");
  t.Add<double>("--det-length-bias", [](O& o) -> double& { return o.detector.length_bias; },
                "Detections: systematic error of the box length, m");
  t.Add<double>("--det-along-ray-bias", [](O& o) -> double& { return o.detector.along_ray_bias; },
                "Detections: systematic position error along the viewing ray, m (+ = farther)");
  t.Add<double>("--det-yaw-sigma-a", [](O& o) -> double& { return o.detector.yaw_sigma_deg_a; },
                "Detections: yaw error std. dev. a + b d: a, deg");
  t.Add<double>("--det-yaw-sigma-b", [](O& o) -> double& { return o.detector.yaw_sigma_deg_b; },
                "Detections: ... b, deg per m");
  t.Add<double>("--det-flip", [](O& o) -> double& { return o.detector.flip_probability; },
                "Detections: share turned by 180 degrees");
  t.Add<double>("--det-flip-run", [](O& o) -> double& { return o.detector.flip_mean_run_frames; },
                "Detections: mean run of a flip, frames (0 = independent per frame)");
  t.Add<double>("--det-miss", [](O& o) -> double& { return o.detector.miss_probability; },
                "Detections: share of visible cars missed");
  t.Add<double>("--det-miss-run", [](O& o) -> double& { return o.detector.miss_mean_run_frames; },
                "Detections: mean run of a miss, frames (0 = independent per frame)");
  t.Add<double>("--det-correlation", [](O& o) -> double& { return o.detector.correlation_frames; },
                "Detections: time constant of the correlated errors, frames (0 = white)");
  t.Add<double>("--det-false-positives", [](O& o) -> double& { return o.detector.false_positives_per_frame; },
                "Detections: mean false positives per frame on clutter");
  t.Add<double>("--det-false-positive-run",
                [](O& o) -> double& { return o.detector.false_positive_mean_run_frames; },
                "Detections: mean lifetime of a false positive, frames");
  t.Add<double>("--det-box-sigma", [](O& o) -> double& { return o.detector.box_sigma_px; },
                "Detections: 2D box corner noise std. dev., px");
  t.Add<int>("--det-min-pixels", [](O& o) -> int& { return o.detector.min_pixels; },
             "Detections: cars with fewer visible pixels are never detected");
  AddCommonOptions(command);
  command->callback([args, command] {
    SynthOptions preset = args->preset == "clean" ? SynthOptions::Clean() : SynthOptions();
    if (!args->detector_profile.empty()) preset.detector = DetectorProfile(args->detector_profile);
    SynthOptions options = args->table->Apply(preset);
    options.output_folder = args->options.output_folder;
    options.disparity =
        args->disparity == "true" ? DisparitySource::kTrueWithNoise : DisparitySource::kStereoSgbm;
    if (args->no_shadows) options.shadows = false;
    if (args->layout == "kitti-tracking") options.layout = SynthLayout::kKittiTracking;
    options.show_progress = GetLogLevel() <= LogLevel::kInfo;
    (void)command;
    const std::vector<SynthCar> cars = LoadSynthCars(args->cars);
    const SynthSummary summary = SynthesizeSequences(options, cars);
    std::cout << summary.BriefReport() << "\nwrote " << options.output_folder << std::endl;
  });
}

}  // namespace samp::tools
