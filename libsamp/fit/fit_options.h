// Options of the track fitter (TrackFitter, fitter.h): every field with its
// default and its rule (Check()).
#pragma once

#include <ceres/types.h>

#include <string>

#include "libsamp/fit/motion_model.h"
#include "libsamp/fit/costs/data_cost.h"

namespace samp {

// Weighting of the data term against the priors (FitOptions::data_weighting).
enum class DataWeighting { kMean, kEffective };
const char* DataWeightingName(DataWeighting weighting);  // "mean", "effective"
DataWeighting ParseDataWeighting(const std::string& name);  // throws samp::Error for an unknown name

struct FitOptions {
  // Single-frame mode: independent shape and pose per frame, no motion term.
  bool single_frame = false;
  // Hard-EM passes after the first solve (re-association + solve), >= 0.
  int em_iterations = 1;
  // sigma_d of every point is multiplied by this in the first solve (uncertain association), >= 1.
  double em_initial_sigma_scale = 2.0;
  // Initial association: candidate points within this distance of the detection's box centre, m.
  double association_radius = 3.0;
  // EM association: |phi_z| at the fitted pose below this, m ...
  double em_distance_threshold = 0.3;
  // ... and inside the fitted shape's box enlarged by this margin, m.
  double em_box_margin = 0.3;
  // Frames with fewer associated points get no data term (motion carries them).
  int min_points_per_frame = 10;
  // At most this many of a frame's associated points enter a solve (an even,
  // deterministic subsample; 0 = all). The data weight stays that of all the
  // associated points (kEffective: N_eff of the whole association; kMean: a
  // mean), so the cap changes the cost's sampling, not the prior/data
  // balance. Stereo errors are correlated over ~correlation_area_px pixels, so
  // beyond a few points per correlation area more points add time, not
  // information: 250 is about N_eff of a near car's frame (5,000 candidates
  // of 4 pixels each / 80 px); measured on the street benchmark's first seed
  // in docs/fitting.md ("Points per solve").
  int max_solve_points_per_frame = 250;
  // Data blocks compressed to R + 5 residuals with the same cost, gradient and
  // Gauss-Newton matrix (CompressedDataCost; much faster); false = N residuals.
  bool compress_data_blocks = true;
  // Data term (costs/): kRayDepth (default; costs/ray_depth.h) = the
  // distance along each point's viewing ray to the shape's surface, with the
  // mixture robustifier below; kPaper = phi at the point (SAMP;
  // costs/point_sdf.h); kDisparity (costs/disparity.h) compares each point's
  // disparity with that of the shape's visible surface on its ray (robust
  // mixture). Measured on the realistic
  // street benchmark in docs/fitting.md ("Choosing the defaults").
  DataTerm data_term = DataTerm::kRayDepth;
  // How a frame's data term is weighted against the priors (docs/fitting.md,
  // "Prior/data balance"): kEffective = each frame counts its effective
  // number of independent observations N_eff = N pixels_per_point /
  // correlation_area_px (the negative log-posterior), motion and ground terms
  // count once per frame; kMean = the paper's (1/T) sum_t (1/N_t) sum_i.
  DataWeighting data_weighting = DataWeighting::kEffective;
  // Image area (px) over which stereo errors are correlated (kEffective):
  // measured on SGBM car pixels by tools/stereo_error_correlation.py (median
  // 78.5 px over 52 car-frames; docs/fitting.md).
  double correlation_area_px = 80.0;
  // Huber threshold of the kPaper / kRayDepth data terms, in units of sigma_d.
  double huber_threshold = 1.0;
  // kPaper / kRayDepth: the mixture robustifier (threshold outlier_threshold)
  // instead of Huber (DataCostOptions::mixture_loss).
  bool mixture_loss = true;
  // kDisparity: silhouette uncertainty of rays that miss the shape, px; the
  // inlier/outlier threshold s_0 of the mixture, in sigma (also the EM gate).
  double silhouette_sigma_px = 2.0;
  double outlier_threshold = 3.0;
  // Standard deviation of the car's height above that frame's road plane, m.
  double sigma_ground = 0.1;
  // Weight lambda of the shape prior lambda sum (z_i / sigma_i)^2.
  double shape_prior_weight = 1.0;
  // The detections' box sizes as observations of the shape (docs/fitting.md,
  // "Detected size"; costs/detection_size.h): std. dev. of a detected length,
  // height and width, m (0 = the term is off, as in the paper). Default: a
  // stereo 3D detector's ~0.3 m (the synthetic detector model's,
  // docs/synthetic.md; the tracker's TrackerOptions::size_sigma).
  double detection_size_sigma = 0.3;
  // The detector's box convention (docs/detector_calibration.md, "Box
  // conventions"; costs/detection_size.h): its box minus the shape's inside
  // box, per dimension, m (KITTI's boxes exclude the mirrors that CAD extents
  // include: a width bias < 0). samp fit's self-calibration estimates them.
  double detection_length_bias = 0.0;
  double detection_height_bias = 0.0;
  double detection_width_bias = 0.0;
  // The detector's systematic error of the bottom centre along the horizontal
  // viewing ray, m (> 0: boxes too far away; costs/detection_position.h).
  double detection_along_bias = 0.0;
  // The detections' box positions as observations of the poses
  // (docs/fitting.md, "Detected position"; costs/detection_position.h), with
  // the detector noise model's covariance (TrackFrame::detection_covariance:
  // the tracker's --tracker-*-sigma) and the correlation below; false = off
  // (the paper: detections only initialise the fit).
  bool detection_position = true;
  // Within this many of its standard deviations (Mahalanobis distance of the
  // frame's origin from its detection) a detected position does not pull;
  // beyond, the term grows as (m - k)^2 instead of m^2 (DeadZoneLoss,
  // costs/detection_position.h). The term then picks the minimum of the data
  // term near the detection without pulling the fit inside it (docs/results.md,
  // "The detected-position term across detectors"); 0 = the plain Gaussian term.
  double detection_position_dead_zone = 1.0;
  // A detector errs the same way for a few frames: consecutive detections'
  // errors correlate as exp(-1 / tau), tau = this many frames (0 = white), so a
  // track's T detections count T (1 - rho) / (1 + rho) independent ones
  // (an AR(1) mean), and the initial speed's significance counts the drift
  // such errors make (docs/fitting.md "Initialisation"). Default: the 3
  // frames of the synthetic detector model (docs/synthetic.md).
  double detection_correlation_frames = 3.0;
  // Motion-model thresholds: |v| < standing_speed -> standing (m/s);
  // |omega| < straight_yaw_rate -> straight line (rad/s), else circular arc.
  double standing_speed = 1.0;
  double straight_yaw_rate = 0.05;
  // Initialisation: a track whose displacement points more than this far off the
  // detections' length axis (radians, either direction) is taken as standing.
  double max_motion_off_axis = 0.5;
  // Initialisation: a track is taken as moving only when its speed (Theil-Sen
  // fit of the detections' positions over time) exceeds this many standard
  // deviations of the estimate (from the scatter of the positions about the fit).
  double min_speed_significance = 3.0;
  // A frame whose fitted position lies farther than this from its initial
  // one (the detection on the road) has diverged (e.g. a single-frame solve
  // on clutter ran away): it is reset to the initial pose (single-frame mode:
  // and the mean shape) and counted in FitSummary::num_frames_reset, m.
  double max_position_change = 5.0;
  MotionNoise motion_noise;
  // Ceres: iterations per solve, tolerances, linear solver
  // ("sparse_normal_cholesky", "dense_schur", "iterative_schur", "dense_qr").
  int max_iterations = 50;
  // End a solve after this many consecutive rejected steps (0 = never): the
  // cost is then at a kink of the residuals (ray distance: rays switching
  // between meeting and missing the surface). One is enough: the trust region
  // is then so wide that LM's damping is negligible, and a retry takes almost
  // the same step (docs/fitting.md, "Solver").
  int max_rejected_steps = 1;
  double function_tolerance = 1e-6;
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;
  std::string linear_solver = "sparse_normal_cholesky";
  // Threads Ceres uses inside one solve (tracks are parallelised by the caller).
  int num_threads = 1;
  // Keep the associated points in the result (for the aligned-points PLY).
  bool keep_points = true;

  // Throws samp::Error naming the field and the rule it broke.
  void Check() const;
};

// FitOptions::linear_solver as Ceres' type. Throws samp::Error naming the
// field for an unknown solver or one the fitter does not use.
ceres::LinearSolverType LinearSolverTypeOf(const std::string& name);

}  // namespace samp
