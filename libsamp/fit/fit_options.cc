#include "libsamp/fit/fit_options.h"

#include <ceres/types.h>

#include <cctype>
#include <cmath>

#include "libsamp/core/error.h"
#include "libsamp/core/pose.h"

namespace samp {

ceres::LinearSolverType LinearSolverTypeOf(const std::string& name) {
  std::string upper = name;
  for (char& c : upper) c = char(std::toupper(static_cast<unsigned char>(c)));
  ceres::LinearSolverType type;
  SAMP_CHECK(ceres::StringToLinearSolverType(upper, &type))
      << "FitOptions.linear_solver: unknown solver '" << name << "'";
  SAMP_CHECK(type != ceres::DENSE_NORMAL_CHOLESKY && type != ceres::CGNR)
      << "FitOptions.linear_solver: use sparse_normal_cholesky, dense_schur, iterative_schur or "
         "dense_qr, not '"
      << name << "'";
  return type;
}

const char* DataWeightingName(DataWeighting weighting) {
  return weighting == DataWeighting::kMean ? "mean" : "effective";
}

DataWeighting ParseDataWeighting(const std::string& name) {
  if (name == "mean") return DataWeighting::kMean;
  if (name == "effective") return DataWeighting::kEffective;
  SAMP_THROW() << "unknown data weighting '" << name << "' (mean, effective)";
}

void FitOptions::Check() const {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  SAMP_CHECK(em_iterations >= 0) << "FitOptions.em_iterations must be >= 0, got " << em_iterations;
  SAMP_CHECK(std::isfinite(em_initial_sigma_scale) && em_initial_sigma_scale >= 1.0)
      << "FitOptions.em_initial_sigma_scale must be >= 1, got " << em_initial_sigma_scale;
  SAMP_CHECK(positive(association_radius)) << "FitOptions.association_radius must be > 0";
  SAMP_CHECK(positive(em_distance_threshold)) << "FitOptions.em_distance_threshold must be > 0";
  SAMP_CHECK(std::isfinite(em_box_margin) && em_box_margin >= 0.0)
      << "FitOptions.em_box_margin must be >= 0";
  SAMP_CHECK(min_points_per_frame >= 1) << "FitOptions.min_points_per_frame must be >= 1";
  SAMP_CHECK(max_solve_points_per_frame == 0 || max_solve_points_per_frame >= min_points_per_frame)
      << "FitOptions.max_solve_points_per_frame must be 0 (all) or >= min_points_per_frame ("
      << min_points_per_frame << "), got " << max_solve_points_per_frame;
  SAMP_CHECK(positive(huber_threshold)) << "FitOptions.huber_threshold must be > 0";
  SAMP_CHECK(positive(correlation_area_px)) << "FitOptions.correlation_area_px must be > 0";
  SAMP_CHECK(positive(silhouette_sigma_px)) << "FitOptions.silhouette_sigma_px must be > 0";
  SAMP_CHECK(positive(outlier_threshold)) << "FitOptions.outlier_threshold must be > 0";
  SAMP_CHECK(positive(sigma_ground)) << "FitOptions.sigma_ground must be > 0";
  SAMP_CHECK(std::isfinite(shape_prior_weight) && shape_prior_weight >= 0.0)
      << "FitOptions.shape_prior_weight must be >= 0";
  SAMP_CHECK(std::isfinite(detection_size_sigma) && detection_size_sigma >= 0.0)
      << "FitOptions.detection_size_sigma must be >= 0 (0 = off)";
  SAMP_CHECK(std::isfinite(detection_correlation_frames) && detection_correlation_frames >= 0.0)
      << "FitOptions.detection_correlation_frames must be >= 0";
  SAMP_CHECK(std::isfinite(standing_speed) && standing_speed >= 0.0)
      << "FitOptions.standing_speed must be >= 0";
  SAMP_CHECK(max_motion_off_axis > 0.0 && max_motion_off_axis <= kPi / 2)
      << "FitOptions.max_motion_off_axis must be in (0, pi/2]";
  SAMP_CHECK(positive(max_position_change)) << "FitOptions.max_position_change must be > 0";
  SAMP_CHECK(std::isfinite(min_speed_significance) && min_speed_significance >= 0.0)
      << "FitOptions.min_speed_significance must be >= 0";
  SAMP_CHECK(std::isfinite(straight_yaw_rate) && straight_yaw_rate >= 0.0)
      << "FitOptions.straight_yaw_rate must be >= 0";
  motion_noise.Check();
  SAMP_CHECK(max_iterations >= 1) << "FitOptions.max_iterations must be >= 1";
  SAMP_CHECK(max_rejected_steps >= 0) << "FitOptions.max_rejected_steps must be >= 0";
  SAMP_CHECK(function_tolerance >= 0 && gradient_tolerance >= 0 && parameter_tolerance >= 0)
      << "FitOptions tolerances must be >= 0";
  LinearSolverTypeOf(linear_solver);
  SAMP_CHECK(num_threads >= 1) << "FitOptions.num_threads must be >= 1";
}

}  // namespace samp
