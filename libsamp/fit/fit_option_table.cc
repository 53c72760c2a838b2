#include "libsamp/fit/fit_option_table.h"

namespace samp {

namespace {

OptionTable<MotionNoise> MakeMotionNoiseTable() {
  using M = MotionNoise;
  OptionTable<M> t("MotionNoise");
  t.Add("speed_noise", &M::speed_noise, "velocity random walk: sigma_v = speed_noise sqrt(dt), m/s/sqrt(s)")
      .NonNegative();
  t.Add("yaw_rate_noise", &M::yaw_rate_noise,
        "yaw-rate random walk: sigma_omega = yaw_rate_noise sqrt(dt), rad/s/sqrt(s)")
      .NonNegative();
  t.Add("sigma_position", &M::sigma_position, "constant std. dev. of the predicted horizontal position, m")
      .Positive();
  t.Add("sigma_height", &M::sigma_height, "constant std. dev. of the predicted height, m").Positive();
  t.Add("sigma_yaw", &M::sigma_yaw, "constant std. dev. of the predicted yaw, rad").Positive();
  t.Add("sigma_speed", &M::sigma_speed, "constant std. dev. of the predicted speed, m/s").Positive();
  t.Add("sigma_yaw_rate", &M::sigma_yaw_rate, "constant std. dev. of the predicted yaw rate, rad/s").Positive();
  return t;
}

OptionTable<FitOptions> MakeFitTable() {
  using F = FitOptions;
  OptionTable<F> t("FitOptions");
  t.Add("single_frame", &F::single_frame, "GCPR 2016 mode: a shape per frame, no motion term");
  t.Add("em_iterations", &F::em_iterations,
        "hard-EM passes after the first solve (re-associate the points with the fitted trajectory, solve again)")
      .AtLeast(0);
  t.Add("em_initial_sigma_scale", &F::em_initial_sigma_scale,
        "sigma_d multiplier of the first solve (uncertain association)")
      .AtLeast(1);
  t.Add("association_radius", &F::association_radius,
        "initial association: points within this distance of the detection's box centre, m")
      .Positive();
  t.Add("em_distance_threshold", &F::em_distance_threshold, "EM: largest |phi_z| of a kept point, m").Positive();
  t.Add("em_box_margin", &F::em_box_margin, "EM: margin around the fitted shape's box, m").NonNegative();
  t.Add("min_points_per_frame", &F::min_points_per_frame, "a frame with fewer points gets no data term")
      .AtLeast(1);
  t.Add("max_solve_points_per_frame", &F::max_solve_points_per_frame,
        "at most this many of a frame's associated points enter a solve (even subsample, the weight of all; "
        "0 = all)")
      .NonNegative()
      .Rule("0 (all) or >= min_points_per_frame",
            [](const F& o) {
              return o.max_solve_points_per_frame == 0 || o.max_solve_points_per_frame >= o.min_points_per_frame;
            })
      .Deprecated("max-solve-points");
  t.Add("compress_data_blocks", &F::compress_data_blocks,
        "data blocks of R + 5 rows with the same cost, gradient and Gauss-Newton matrix; false = N rows");
  t.AddChoice("data_term", &F::data_term, DataTermName, ParseDataTerm, {"ray-depth", "paper", "disparity"},
              "ray-depth: distance along the viewing ray to the surface; paper: phi at the point (SAMP); "
              "disparity: the point's vs the visible surface's disparity")
      .Deprecated("ray-depth-inside", "ray-depth");
  t.AddChoice("data_weighting", &F::data_weighting, DataWeightingName, ParseDataWeighting, {"effective", "mean"},
              "effective: each frame counts its effective number of observations N_eff; mean: the paper's "
              "(1/T) sum_t mean over points")
      .Deprecated("weighting");
  t.Add("correlation_area_px", &F::correlation_area_px,
        "image area over which stereo errors are correlated (effective weighting), px")
      .Positive()
      .Deprecated("correlation-area");
  t.Add("huber_threshold", &F::huber_threshold, "Huber threshold of the paper / ray-depth terms, in sigma_d")
      .Positive()
      .Deprecated("huber");
  t.Add("mixture_loss", &F::mixture_loss,
        "paper / ray-depth terms: the Gaussian + uniform mixture robustifier (threshold outlier_threshold) "
        "instead of Huber")
      .OffFlag("huber-loss");
  t.Add("silhouette_sigma_px", &F::silhouette_sigma_px,
        "disparity term: std. dev. of a ray's silhouette clearance, px")
      .Positive();
  t.Add("outlier_threshold", &F::outlier_threshold,
        "mixture robustifier: inlier/outlier threshold s_0 (and the disparity term's EM gate), in sigma")
      .Positive();
  t.Add("sigma_ground", &F::sigma_ground, "ground prior: std. dev. of the height above the road plane, m")
      .Positive();
  t.Add("shape_prior_weight", &F::shape_prior_weight, "lambda of the shape prior lambda sum (z_i / sigma_i)^2")
      .NonNegative();
  t.Add("detection_size_sigma", &F::detection_size_sigma,
        "std. dev. of the detected length, height and width, which observe the shape, m; 0 = off (the paper)")
      .NonNegative();
  t.AddOptional("detection_length_bias", &F::detection_length_bias,
                "the detector's box convention: detected length minus the shape's, m (self-calibration "
                "estimates it)");
  t.AddOptional("detection_height_bias", &F::detection_height_bias,
                "the detector's box convention: detected height minus the shape's, m");
  t.AddOptional("detection_width_bias", &F::detection_width_bias,
                "the detector's box convention: detected width minus the shape's, m (KITTI boxes exclude "
                "the mirrors: < 0)");
  t.AddOptional("detection_along_bias", &F::detection_along_bias,
                "the detector's systematic error of the box position along the viewing ray, m (> 0: too far)");
  t.Add("detection_correlation_frames", &F::detection_correlation_frames,
        "tau of the detector's AR(1) errors exp(-1/tau), frames, for the detected-position term and the initial speed's significance; 0 = independent (self-calibration: as measured)")
      .NonNegative()
      .Deprecated("detection-correlation");
  t.Add("detection_position", &F::detection_position,
        "the detected box positions observe the poses (the tracker's detector noise model); false = off "
        "(the paper)");
  t.Add("detection_position_dead_zone", &F::detection_position_dead_zone,
        "within this many standard deviations of its detection a frame's origin feels no pull of the "
        "detected position; 0 = the plain Gaussian term")
      .NonNegative();
  t.Add("standing_speed", &F::standing_speed, "below this speed the standing motion model is used, m/s")
      .NonNegative();
  t.Add("straight_yaw_rate", &F::straight_yaw_rate,
        "below this yaw rate the straight-line model is used, else the arc, rad/s")
      .NonNegative();
  t.Add("max_motion_off_axis", &F::max_motion_off_axis,
        "initialisation: a displacement further off the length axis is taken as standing, rad")
      .Above(0)
      .AtMost(M_PI / 2);
  t.Add("min_speed_significance", &F::min_speed_significance,
        "initialisation: moving only when the speed exceeds this many standard deviations")
      .NonNegative();
  t.Add("max_position_change", &F::max_position_change,
        "a frame fitted farther from its initial pose has diverged and is reset, m")
      .Positive();
  t.AddNested("motion_noise", &F::motion_noise, MotionNoiseOptionTable(), "motion-");
  t.Add("max_iterations", &F::max_iterations, "Levenberg-Marquardt iterations per solve").AtLeast(1);
  t.Add("max_rejected_steps", &F::max_rejected_steps,
        "end a solve after this many consecutive rejected steps (0 = never)")
      .AtLeast(0);
  t.Add("function_tolerance", &F::function_tolerance, "Ceres function tolerance").NonNegative();
  t.Add("gradient_tolerance", &F::gradient_tolerance, "Ceres gradient tolerance").NonNegative();
  t.Add("parameter_tolerance", &F::parameter_tolerance, "Ceres parameter tolerance").NonNegative();
  t.Add("linear_solver", &F::linear_solver, "Ceres linear solver")
      .Choices({"sparse_normal_cholesky", "dense_schur", "iterative_schur", "dense_qr"});
  t.Add("num_threads", &F::num_threads, "threads Ceres uses inside one solve (tracks run in parallel)")
      .AtLeast(1)
      .Flag("solver-threads");
  t.Add("keep_points", &F::keep_points,
        "keep the associated points in the result (library callers; samp fit writes them as _points.ply)")
      .Internal();
  return t;
}

}  // namespace

const OptionTable<MotionNoise>& MotionNoiseOptionTable() {
  static const OptionTable<MotionNoise> table = MakeMotionNoiseTable();
  return table;
}

const OptionTable<FitOptions>& FitOptionTable() {
  static const OptionTable<FitOptions> table = MakeFitTable();
  return table;
}

void OptionFields(OptionsJson& io, MotionNoise& o) { MotionNoiseOptionTable().Json(io, o); }
void OptionFields(OptionsJson& io, FitOptions& o) { FitOptionTable().Json(io, o); }

void MotionNoise::Check() const { MotionNoiseOptionTable().Check(*this); }
void FitOptions::Check() const { FitOptionTable().Check(*this); }

}  // namespace samp
