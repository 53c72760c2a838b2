// `samp synth`: CAD cars -> synthetic KITTI-like stereo sequences with ground truth.
#include <iostream>
#include <memory>

#include "libsamp/core/log.h"
#include "libsamp/eval/synth.h"
#include "tools/samp/commands.h"

namespace samp::tools {

void RegisterSynthCommand(CLI::App* app) {
  struct Args {
    SynthOptions options;
    SynthCarSource cars;
    std::string disparity = "sgbm";
  };
  auto args = std::make_shared<Args>();
  SynthOptions& o = args->options;
  SynthCarSource& c = args->cars;
  CLI::App* command = app->add_subcommand(
      "synth",
      "Synthesize KITTI-like stereo sequences of CAD cars with ground truth (docs/synthetic.md).\n"
      "Writes OUT/<seq>/ in the layout `samp fit` reads (calib, image_2, image_3, disparity,\n"
      "detections, planes, poses) plus OUT/<seq>/gt/ (label_02, depth, obj_map, meshes, cars.json).\n"
      "Same options and seed give the same files.");
  command->add_option("-o,--out", o.output_folder, "Output folder (one sub-folder per sequence)")
      ->required();
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
  command->add_option("--seed", o.seed, "Seed of all random choices")->capture_default_str();
  command->add_option("--sequences", o.num_sequences, "Number of sequences")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--first-sequence", o.first_sequence, "Number of the first sequence (<seq> = %06d)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--cars-per-sequence", o.cars_per_sequence, "Cars per sequence")
      ->capture_default_str()
      ->check(CLI::Range(1, 20));
  command->add_option("--frames", o.num_frames, "Frames per sequence")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  command->add_option("--fps", o.frame_rate_hz, "Frame rate, Hz")->capture_default_str()->check(CLI::PositiveNumber);
  command->add_option("--width", o.width, "Image width, px")->capture_default_str();
  command->add_option("--height", o.height, "Image height, px")->capture_default_str();
  command->add_option("--focal", o.focal_px, "Focal length, px")->capture_default_str();
  command->add_option("--cx", o.cx_px, "Principal point x, px")->capture_default_str();
  command->add_option("--cy", o.cy_px, "Principal point y, px")->capture_default_str();
  command->add_option("--baseline", o.baseline, "Stereo baseline, m")->capture_default_str();
  command->add_option("--camera-height", o.camera_height, "Camera height above the road, m")
      ->capture_default_str();
  command->add_option("--min-distance", o.min_distance, "Closest car distance at the middle frame, m")
      ->capture_default_str();
  command->add_option("--max-distance", o.max_distance, "Farthest car distance at the middle frame, m")
      ->capture_default_str();
  command->add_option("--max-ego-speed", o.max_ego_speed, "Maximal ego speed, m/s")->capture_default_str();
  command->add_option("--disparity", args->disparity,
                      "Disparity source: 'sgbm' (OpenCV StereoSGBM on the rendered pair) or 'true' "
                      "(true disparity + the documented noise model, fast)")
      ->capture_default_str()
      ->check(CLI::IsMember({"sgbm", "true"}));
  command->add_option("--image-noise", o.image_noise_sigma, "Image noise std. dev., grey levels")
      ->capture_default_str();
  command->add_option("--disparity-noise", o.disparity_sigma_px,
                      "'true' mode: disparity noise std. dev. on the background, px")
      ->capture_default_str();
  command->add_option("--car-disparity-noise", o.car_disparity_sigma_px,
                      "'true' mode: disparity noise std. dev. on cars, px")
      ->capture_default_str();
  command->add_option("--invalid-fraction", o.invalid_fraction, "'true' mode: share of invalid pixels")
      ->capture_default_str();
  command->add_option("--outlier-fraction", o.outlier_fraction, "'true' mode: share of uniform outliers")
      ->capture_default_str();
  command->add_option("--det-flip", o.det_flip_probability, "Detections: probability of a 180-degree yaw flip")
      ->capture_default_str();
  command->add_option("--det-miss", o.det_miss_probability, "Detections: probability of a miss")
      ->capture_default_str();
  command->add_option("--det-depth-sigma", o.det_depth_sigma_b,
                      "Detections: quadratic coefficient b of the depth noise a + b d^2, m^-1")
      ->capture_default_str();
  command->add_option("--det-yaw-sigma", o.det_yaw_sigma_deg_a,
                      "Detections: constant part of the yaw noise std. dev., deg")
      ->capture_default_str();
  AddCommonOptions(command);
  command->callback([args] {
    SynthOptions options = args->options;
    options.disparity =
        args->disparity == "true" ? DisparitySource::kTrueWithNoise : DisparitySource::kStereoSgbm;
    options.show_progress = GetLogLevel() <= LogLevel::kInfo;
    const std::vector<SynthCar> cars = LoadSynthCars(args->cars);
    const SynthSummary summary = SynthesizeSequences(options, cars);
    std::cout << summary.BriefReport() << "\nwrote " << options.output_folder << std::endl;
  });
}

}  // namespace samp::tools
