#include "libsamp/synth/synth_option_table.h"

namespace samp {

namespace {

const char* DisparitySourceName(DisparitySource d) {
  return d == DisparitySource::kStereoSgbm ? "sgbm" : "true+noise";
}
DisparitySource ParseDisparitySource(const std::string& name) {
  if (name == "sgbm") return DisparitySource::kStereoSgbm;
  if (name == "true" || name == "true+noise") return DisparitySource::kTrueWithNoise;
  SAMP_THROW() << "unknown disparity source '" << name << "' (sgbm, true)";
}
const char* SynthSceneName(SynthScene s) { return s == SynthScene::kStreet ? "street" : "clean"; }
SynthScene ParseSynthScene(const std::string& name) {
  if (name == "street") return SynthScene::kStreet;
  if (name == "clean") return SynthScene::kClean;
  SAMP_THROW() << "unknown scene '" << name << "' (street, clean)";
}
const char* SynthLayoutName(SynthLayout l) { return l == SynthLayout::kSamp ? "samp" : "kitti-tracking"; }
SynthLayout ParseSynthLayout(const std::string& name) {
  if (name == "samp") return SynthLayout::kSamp;
  if (name == "kitti-tracking") return SynthLayout::kKittiTracking;
  SAMP_THROW() << "unknown layout '" << name << "' (samp, kitti-tracking)";
}

OptionTable<StreetOptions> MakeStreetTable() {
  using T = StreetOptions;
  OptionTable<T> t("StreetOptions");
  t.Add("two_lane_probability", &T::two_lane_probability,
        "street: probability of two driving lanes per direction (else one)")
      .AtLeast(0)
      .AtMost(1);
  t.Add("min_lane_width", &T::min_lane_width, "street: minimal lane width, m").AtLeast(2.5);
  t.Add("max_lane_width", &T::max_lane_width, "street: maximal lane width, m")
      .AtMost(5)
      .Rule(">= min_lane_width", [](const T& o) { return o.max_lane_width >= o.min_lane_width; });
  t.Add("right_parking_probability", &T::right_parking_probability,
        "street: probability of a parking lane (2.2 m) on the right")
      .AtLeast(0)
      .AtMost(1);
  t.Add("left_parking_probability", &T::left_parking_probability,
        "street: probability of a parking lane on the left")
      .AtLeast(0)
      .AtMost(1);
  t.Add("kerb_height", &T::kerb_height, "street: kerb height, m").AtLeast(0).AtMost(0.3);
  t.Add("min_sidewalk_width", &T::min_sidewalk_width,
        "street: minimal sidewalk width, m (the rest up to the facade is a front yard)")
      .AtLeast(1);
  t.Add("max_sidewalk_width", &T::max_sidewalk_width, "street: maximal sidewalk width, m")
      .Rule(">= min_sidewalk_width", [](const T& o) { return o.max_sidewalk_width >= o.min_sidewalk_width; });
  t.Add("min_facade_distance", &T::min_facade_distance, "street: minimal facade distance from the kerb, m")
      .Rule(">= min_sidewalk_width", [](const T& o) { return o.min_facade_distance >= o.min_sidewalk_width; });
  t.Add("max_facade_distance", &T::max_facade_distance, "street: maximal facade distance from the kerb, m")
      .Rule(">= min_facade_distance", [](const T& o) { return o.max_facade_distance >= o.min_facade_distance; });
  t.Add("clutter_spacing", &T::clutter_spacing,
        "street: mean spacing of poles, trees, bins, signs, bollards per side, m")
      .Above(0.5);
  t.Add("intersection_probability", &T::intersection_probability,
        "street: probability of a crossing street 15-45 m ahead")
      .AtLeast(0)
      .AtMost(1);
  t.Add("min_parked_gap", &T::min_parked_gap, "street: minimal gap between parked cars, m").NonNegative();
  t.Add("max_parked_gap", &T::max_parked_gap, "street: maximal gap between parked cars, m")
      .Rule(">= min_parked_gap", [](const T& o) { return o.max_parked_gap >= o.min_parked_gap; });
  return t;
}

// A flip or miss run: a Markov chain with stationary share p needs a mean run >= max(1, p / (1 - p)).
bool RunFits(double probability, double run) {
  return run == 0.0 || (run >= 1.0 && run >= probability / (1.0 - probability));
}

OptionTable<DetectorModelOptions> MakeDetectorTable() {
  using D = DetectorModelOptions;
  OptionTable<D> t("DetectorModelOptions");
  t.AddOptional("profile", &D::profile,
                "the named profile these options came from (`samp synth --detector-profile`; a record only)")
      .Internal();
  t.Add("ray_sigma_a", &D::ray_sigma_a,
        "position error std. dev. along the horizontal viewing ray a + b d + c d^2: a, m")
      .NonNegative();
  t.Add("ray_sigma_b", &D::ray_sigma_b, "... b, m per m").NonNegative();
  t.Add("ray_sigma_c", &D::ray_sigma_c, "... c, 1/m").NonNegative();
  t.Add("lateral_sigma_a", &D::lateral_sigma_a, "horizontal error std. dev. across the ray a + b d: a, m")
      .NonNegative();
  t.Add("lateral_sigma_b", &D::lateral_sigma_b, "... b, m per m").NonNegative();
  t.Add("vertical_sigma", &D::vertical_sigma, "vertical position error std. dev., m").NonNegative();
  t.Add("size_sigma", &D::size_sigma, "std. dev. of each of h, w, l, m").NonNegative();
  t.Add("relative_size_sigma", &D::relative_size_sigma,
        "relative std. dev. of each of h, w, l (added to size_sigma)")
      .NonNegative();
  t.AddOptional("height_bias", &D::height_bias, "systematic error of the box height, detected - true, m");
  t.AddOptional("width_bias", &D::width_bias,
                "systematic error of the box width, m (KITTI boxes exclude mirrors: about -0.25)");
  t.AddOptional("length_bias", &D::length_bias, "systematic error of the box length, m");
  t.AddOptional("along_ray_bias", &D::along_ray_bias,
                "systematic position error along the viewing ray, m (+ = farther)");
  t.Add("yaw_sigma_deg_a", &D::yaw_sigma_deg_a, "yaw error std. dev. a + b d: a, deg")
      .Flag("yaw-sigma-a")
      .NonNegative();
  t.Add("yaw_sigma_deg_b", &D::yaw_sigma_deg_b, "... b, deg per m").Flag("yaw-sigma-b").NonNegative();
  t.Add("flip_probability", &D::flip_probability, "share of detections turned by 180 degrees")
      .Flag("flip")
      .AtLeast(0)
      .Below(1);
  t.Add("flip_mean_run_frames", &D::flip_mean_run_frames,
        "mean run of a flip, frames (0 = independent per frame)")
      .Flag("flip-run")
      .Rule("0 (independent) or >= max(1, p / (1 - p)) frames",
            [](const D& o) { return RunFits(o.flip_probability, o.flip_mean_run_frames); });
  t.Add("miss_probability", &D::miss_probability, "share of visible cars missed").Flag("miss").AtLeast(0).Below(1);
  t.Add("miss_mean_run_frames", &D::miss_mean_run_frames,
        "mean run of a miss, frames (0 = independent per frame)")
      .Flag("miss-run")
      .Rule("0 (independent) or >= max(1, p / (1 - p)) frames",
            [](const D& o) { return RunFits(o.miss_probability, o.miss_mean_run_frames); });
  t.Add("correlation_frames", &D::correlation_frames,
        "time constant of the AR(1) errors (position, size, yaw), frames (0 = white)")
      .Flag("correlation")
      .NonNegative();
  t.Add("false_positives_per_frame", &D::false_positives_per_frame,
        "mean false positives per frame on clutter (poles, trees, bins, walls, facades, parked rows)")
      .Flag("false-positives")
      .NonNegative();
  t.Add("false_positive_mean_run_frames", &D::false_positive_mean_run_frames,
        "mean lifetime of a false positive, frames")
      .Flag("false-positive-run")
      .AtLeast(1);
  t.Add("box_sigma_px", &D::box_sigma_px, "2D box corner noise std. dev., px").Flag("box-sigma").NonNegative();
  t.Add("min_pixels", &D::min_pixels, "cars with fewer visible pixels are never detected").NonNegative();
  return t;
}

OptionTable<SynthOptions> MakeSynthTable() {
  using O = SynthOptions;
  OptionTable<O> t("SynthOptions");
  // Sequences and camera.
  t.Add("seed", &O::seed, "seed of all random choices (scenes, motion, noise)");
  t.Add("num_sequences", &O::num_sequences, "number of sequences").Flag("sequences").AtLeast(1);
  t.Add("first_sequence", &O::first_sequence,
        "number of the first sequence (<seq> = %06d; %04d in KITTI tracking's layout)")
      .AtLeast(0)
      .Rule("<= 1000000 - num_sequences",
            [](const O& o) { return o.first_sequence + o.num_sequences <= 1000000; })
      .Rule("<= 10000 - num_sequences in KITTI tracking's layout (4-digit names)", [](const O& o) {
        return o.layout == SynthLayout::kSamp || o.first_sequence + o.num_sequences <= 10000;
      });
  t.AddChoice("scene", &O::scene, SynthSceneName, ParseSynthScene, {"street", "clean"},
              "street: realistic streets; clean: the first benchmark's scenes (set with every other default of "
              "the clean preset by `samp synth --preset`)")
      .Internal();
  t.AddOptionalChoice("layout", &O::layout, SynthLayoutName, ParseSynthLayout, {"samp", "kitti-tracking"},
                      "folders written: samp (OUT/<seq>/) or kitti-tracking (KITTI tracking's own: "
                      "OUT/training/image_02|image_03/<seq>/, calib/, oxts/, label_02/, and the detections "
                      "OUT/detections/<seq>.txt; docs/sequence_format.md)");
  t.Add("num_frames", &O::num_frames, "frames per sequence").Flag("frames").AtLeast(1).AtMost(1000);
  t.Add("frame_rate_hz", &O::frame_rate_hz, "frame rate, Hz").Flag("fps").Positive();
  t.Add("width", &O::width, "image width, px").AtLeast(32);
  t.Add("height", &O::height, "image height, px").AtLeast(32);
  t.Add("focal_px", &O::focal_px, "focal length, px").Flag("focal").Positive();
  t.Add("cx_px", &O::cx_px, "principal point x, px")
      .Flag("cx")
      .Positive()
      .Rule("< width", [](const O& o) { return o.cx_px < o.width; });
  t.Add("cy_px", &O::cy_px, "principal point y, px")
      .Flag("cy")
      .Positive()
      .Rule("< height", [](const O& o) { return o.cy_px < o.height; });
  t.Add("baseline", &O::baseline, "stereo baseline, m").Positive();
  t.Add("camera_height", &O::camera_height, "camera height above the road, m").Above(0.5);
  // Cars and motion.
  t.Add("cars_per_sequence", &O::cars_per_sequence, "traffic cars per sequence (moving or waiting)")
      .AtLeast(1)
      .AtMost(20);
  t.Add("parked_cars_per_sequence", &O::parked_cars_per_sequence,
        "street: parked cars per sequence, in rows in the parking lanes")
      .Flag("parked-cars")
      .AtLeast(0)
      .AtMost(12);
  t.Add("standing_share", &O::standing_share, "street: share of the traffic cars that stand (waiting)")
      .NonNegative();
  t.Add("turning_share", &O::turning_share, "street: share of the traffic cars that turn (the rest drive straight)")
      .NonNegative()
      .Rule("<= 1 - standing_share", [](const O& o) { return o.standing_share + o.turning_share <= 1; });
  t.Add("min_distance", &O::min_distance, "closest car distance at the middle frame, m").AtLeast(4);
  t.Add("max_distance", &O::max_distance, "farthest car distance at the middle frame, m")
      .AtMost(150)
      .Rule("> min_distance", [](const O& o) { return o.max_distance > o.min_distance; });
  t.Add("near_share", &O::near_share,
        "street: share of each sequence's cars (parked and traffic) nearer than 20 m at the middle frame; parked "
        "rows and traffic cars are drawn near while the sequence is short of it (a target: placements that find "
        "no room fall back to any distance)")
      .AtLeast(0)
      .AtMost(1);
  t.Add("min_speed", &O::min_speed, "straight cars: minimal speed, m/s").Positive();
  t.Add("max_speed", &O::max_speed, "straight cars: maximal speed, m/s")
      .Rule(">= min_speed", [](const O& o) { return o.max_speed >= o.min_speed; });
  t.Add("min_turn_speed", &O::min_turn_speed, "turning cars: minimal speed, m/s").Positive();
  t.Add("max_turn_speed", &O::max_turn_speed, "turning cars: maximal speed, m/s")
      .Rule(">= min_turn_speed", [](const O& o) { return o.max_turn_speed >= o.min_turn_speed; });
  t.Add("min_yaw_rate", &O::min_yaw_rate, "turning cars: minimal absolute yaw rate, rad/s").Positive();
  t.Add("max_yaw_rate", &O::max_yaw_rate, "turning cars: maximal absolute yaw rate, rad/s")
      .Rule(">= min_yaw_rate", [](const O& o) { return o.max_yaw_rate >= o.min_yaw_rate; });
  t.Add("min_ego_speed", &O::min_ego_speed, "minimal ego speed, m/s").NonNegative();
  t.Add("max_ego_speed", &O::max_ego_speed, "maximal ego speed, m/s")
      .Rule(">= min_ego_speed", [](const O& o) { return o.max_ego_speed >= o.min_ego_speed; });
  t.Add("max_ego_yaw_rate", &O::max_ego_yaw_rate, "maximal absolute ego yaw rate, rad/s").NonNegative();
  t.Add("ego_pitch_sway_deg", &O::ego_pitch_sway_deg,
        "street: ego pitch sway amplitude at the maximal ego speed, deg")
      .Flag("ego-pitch-sway")
      .NonNegative();
  t.Add("ego_roll_sway_deg", &O::ego_roll_sway_deg, "street: ego roll sway amplitude at the maximal ego speed, deg")
      .Flag("ego-roll-sway")
      .NonNegative();
  t.Add("ego_bounce", &O::ego_bounce, "street: ego vertical bounce amplitude at the maximal ego speed, m")
      .NonNegative();
  t.Add("ego_max_pitch_offset_deg", &O::ego_max_pitch_offset_deg,
        "street: maximal constant camera pitch (mounting, load), deg")
      .Flag("ego-pitch-offset")
      .NonNegative();
  // Appearance.
  t.Add("min_sun_elevation_deg", &O::min_sun_elevation_deg, "street: minimal sun elevation, deg")
      .Flag("min-sun-elevation")
      .Above(0);
  t.Add("max_sun_elevation_deg", &O::max_sun_elevation_deg, "street: maximal sun elevation, deg")
      .Flag("max-sun-elevation")
      .AtMost(90)
      .Rule(">= min_sun_elevation_deg", [](const O& o) { return o.max_sun_elevation_deg >= o.min_sun_elevation_deg; });
  t.Add("paint_specular", &O::paint_specular, "street: strength of the sun highlight on the paint").NonNegative();
  t.Add("paint_shininess", &O::paint_shininess, "street: Blinn-Phong exponent of the paint's highlight").AtLeast(1);
  t.Add("paint_fresnel_f0", &O::paint_fresnel_f0, "street: Schlick F0 of the paint's sky reflection")
      .Flag("paint-fresnel")
      .AtLeast(0)
      .Below(1);
  t.Add("glass_fresnel_f0", &O::glass_fresnel_f0, "street: Schlick F0 of the windows' sky reflection")
      .Flag("glass-fresnel")
      .AtLeast(0)
      .Below(1);
  t.Add("paint_texture", &O::paint_texture, "street: relative amplitude of the paint's texture (dirt, orange peel)")
      .NonNegative();
  t.Add("window_interior_albedo", &O::window_interior_albedo,
        "street: mean albedo of the car interior seen through the windows (0 = black glass)")
      .Flag("window-interior")
      .AtLeast(0)
      .AtMost(0.5);
  t.Add("shadows", &O::shadows, "street: cast sun shadows");
  t.Add("image_noise_sigma", &O::image_noise_sigma, "image noise std. dev., grey levels")
      .Flag("image-noise")
      .NonNegative();
  // Stereo.
  t.AddChoice("disparity", &O::disparity, DisparitySourceName, ParseDisparitySource, {"sgbm", "true", "true+noise"},
              "disparity source: sgbm (OpenCV StereoSGBM on the rendered pair) or true (= true+noise: the true "
              "disparity + the noise model below, fast)");
  t.Add("disparity_sigma_px", &O::disparity_sigma_px, "'true' mode: disparity noise std. dev. on the background, px")
      .Flag("disparity-noise")
      .NonNegative();
  t.Add("car_disparity_sigma_px", &O::car_disparity_sigma_px, "'true' mode: disparity noise std. dev. on cars, px")
      .Flag("car-disparity-noise")
      .NonNegative();
  t.Add("invalid_fraction", &O::invalid_fraction, "'true' mode: share of invalid pixels").NonNegative();
  t.Add("outlier_fraction", &O::outlier_fraction, "'true' mode: share of uniform outliers")
      .NonNegative()
      .Rule("<= 1 - invalid_fraction", [](const O& o) { return o.invalid_fraction + o.outlier_fraction <= 1; });
  t.AddNested("street", &O::street, StreetOptionTable(), "");
  t.AddNested("detector", &O::detector, DetectorModelOptionTable(), "det-");
  return t;
}

}  // namespace

const OptionTable<StreetOptions>& StreetOptionTable() {
  static const OptionTable<StreetOptions> table = MakeStreetTable();
  return table;
}

const OptionTable<DetectorModelOptions>& DetectorModelOptionTable() {
  static const OptionTable<DetectorModelOptions> table = MakeDetectorTable();
  return table;
}

const OptionTable<SynthOptions>& SynthOptionTable() {
  static const OptionTable<SynthOptions> table = MakeSynthTable();
  return table;
}

void OptionFields(OptionsJson& io, StreetOptions& o) { StreetOptionTable().Json(io, o); }
void OptionFields(OptionsJson& io, DetectorModelOptions& o) { DetectorModelOptionTable().Json(io, o); }
void OptionFields(OptionsJson& io, SynthOptions& o) { SynthOptionTable().Json(io, o); }

}  // namespace samp
