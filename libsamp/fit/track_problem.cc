#include "libsamp/fit/track_problem.h"

#include <cmath>
#include <memory>

#include "libsamp/fit/costs/compressed_data_cost.h"
#include "libsamp/fit/costs/detection_position.h"
#include "libsamp/fit/costs/detection_size.h"
#include "libsamp/fit/costs/ground.h"
#include "libsamp/fit/costs/motion.h"
#include "libsamp/fit/costs/shape_prior.h"
#include "libsamp/fit/motion_model.h"

namespace samp {

namespace {

// The detected box sizes as observations of each code (costs/detection_size.h),
// the inside box's size linearised about the code the solve starts from.
// Joint mode: every frame's detection observes the one code, each counting
// CorrelatedObservationShare of an observation (correlated detector errors); single-frame
// mode: each frame's code its own detection, once.
void AddDetectionSizeTerms(const ShapeLookup& lookup, const Track& track, const FitOptions& options,
                           double frame_weight, TrackState* state, ceres::Problem* problem) {
  if (options.detection_size_sigma <= 0.0) return;
  const bool single = options.single_frame;
  const double per_frame =
      frame_weight * (single ? 1.0 : CorrelatedObservationShare(int(track.frames.size()),
                                                                options.detection_correlation_frames));
  // Half a sigma: wide enough to smooth the box's voxel kinks, narrow enough to stay local.
  constexpr double kStep = 0.5;
  // Single-frame codes that are equal (all of them in the first solve, from
  // the mean) share one linearisation: 2R + 1 box evaluations each.
  const Eigen::Vector3d bias(options.detection_length_bias, options.detection_height_bias,
                             options.detection_width_bias);  // the box's x, y, z as `detected`
  Eigen::VectorXd linearised_code;
  ShapeLookup::BoxSizeLinearisation lin;
  bool have_lin = false;
  for (int c = 0; c < int(state->codes.size()); ++c) {
    const int first = single ? c : 0;
    const int last = single ? c + 1 : int(track.frames.size());
    for (int k = first; k < last; ++k) {
      const ObjectLabel& d = track.frames[k].detection;
      const Eigen::Vector3d detected(d.length, d.height, d.width);  // the box's x, y, z extent
      if (!(detected.array() > 0.0).all() || !detected.allFinite()) continue;
      if (linearised_code.size() == 0 || linearised_code != state->codes[c]) {
        linearised_code = state->codes[c];
        have_lin = lookup.LineariseInsideBoxSize(linearised_code, kStep, &lin);
      }
      if (!have_lin) continue;
      problem->AddResidualBlock(DetectionSizeCost::Create(state->codes[c], lin.size, lin.jacobian, detected,
                                                          options.detection_size_sigma, per_frame, bias),
                                nullptr, state->codes[c].data());
    }
  }
}

// The detector's along-ray bias of frame f's detection as an offset in the
// world (costs/detection_position.h): along the horizontal viewing ray.
Eigen::Vector3d DetectionBiasInWorld(const TrackFrame& f, const FitOptions& options) {
  if (options.detection_along_bias == 0.0) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d& p = f.detection.position;
  const Eigen::Vector3d ray(p.x(), 0.0, p.z());
  if (!(ray.norm() > 1e-9)) return Eigen::Vector3d::Zero();
  return options.detection_along_bias * (f.world_from_camera.linear() * ray.normalized());
}

// The motion term from frame k - 1 into frame k (joint mode, k >= 1), with
// the model the previous frame's velocities select.
void AddMotionTerm(const Track& track, int k, const FitOptions& options, double frame_weight, TrackState* state,
                   ceres::Problem* problem) {
  const double dt = track.frames[k].time - track.frames[k - 1].time;
  double* prev_pose = state->poses[k - 1].data();
  double* prev_vel = state->velocities[k - 1].data();
  const MotionModel model = SelectMotionModel(prev_vel[0], prev_vel[1], options.standing_speed,
                                              options.straight_yaw_rate);
  state->models[k] = MotionModelName(model);
  const auto sigma = MotionCovariance(model, prev_pose, prev_vel, dt, options.motion_noise);
  problem->AddResidualBlock(MotionCost::Create(model, dt, SqrtInformation(sigma), frame_weight), nullptr,
                            prev_pose, prev_vel, state->poses[k].data(), state->velocities[k].data());
}

// Frame k's data term; returns its number of points (0: too few associated).
int AddDataTerm(const ShapeLookup& lookup, const Track& track, int k, const Association& association,
                double sigma_scale, double frame_weight, const FitOptions& options, TrackState* state,
                ceres::Problem* problem) {
  if (int(association.points.size()) < options.min_points_per_frame) return 0;
  const TrackFrame& f = track.frames[k];
  const int n = int(association.points.size());
  const bool mean = options.data_weighting == DataWeighting::kMean;
  const double data_weight = mean ? frame_weight : EffectivePoints(f, n, options);
  const DataCostOptions cost_options = DataTermOptions(track, f, options, data_weight);
  Association solve = SolveSubsample(association, options.max_solve_points_per_frame);
  for (double& s : solve.sigmas) s *= sigma_scale;
  ceres::CostFunction* cost =
      options.compress_data_blocks ? CompressedDataCost::Create(&lookup, solve.points, solve.sigmas, cost_options)
                                   : MakeDataCost(&lookup, solve.points, solve.sigmas, cost_options).release();
  problem->AddResidualBlock(cost, nullptr, state->codes[options.single_frame ? k : 0].data(),
                            state->poses[k].data());
  return int(solve.points.size());
}

}  // namespace

DataCostOptions DataTermOptions(const Track& track, const TrackFrame& f, const FitOptions& options, double weight) {
  DataCostOptions o;
  o.huber_threshold = options.huber_threshold;
  o.mixture_loss = options.mixture_loss;
  o.weight = weight;
  o.term = options.data_term;
  o.camera_in_world = f.world_from_camera.translation();
  o.camera_axis_in_world = f.world_from_camera.linear().col(2).normalized();
  o.focal_px = track.calibration.camera.fx;
  o.silhouette_sigma_px = options.silhouette_sigma_px;
  o.outlier_threshold = options.outlier_threshold;
  return o;
}

double CorrelatedObservationShare(int num_observations, double tau) {
  if (tau <= 0.0 || num_observations <= 1) return 1.0;
  const double rho = std::exp(-1.0 / tau);
  const int n = num_observations;
  double sum = n;
  double power = 1.0;
  for (int lag = 1; lag < n; ++lag) {
    power *= rho;
    sum += 2.0 * (n - lag) * power;
  }
  return n / sum;
}

int BuildTrackProblem(const ShapeLookup& lookup, const Track& track, const std::vector<Association>& data,
                      double sigma_scale, const FitOptions& options, TrackState* state, ceres::Problem* problem) {
  const int num_frames = int(track.frames.size());
  const bool single = options.single_frame;
  // kMean: the paper's E = (1/T) sum_t [E_data,t (a mean over points) + ...] + E_shape;
  // kEffective: the negative log-posterior, every frame and point counted.
  const double frame_weight = options.data_weighting == DataWeighting::kMean ? 1.0 / num_frames : 1.0;
  for (int c = 0; c < int(state->codes.size()); ++c) {
    problem->AddParameterBlock(state->codes[c].data(), lookup.num_components());
    if (options.shape_prior_weight > 0.0) {
      problem->AddResidualBlock(
          ShapePriorCost::Create(lookup.sigmas(), options.shape_prior_weight * (single ? frame_weight : 1.0)),
          nullptr, state->codes[c].data());
    }
  }
  AddDetectionSizeTerms(lookup, track, options, frame_weight, state, problem);
  // Each frame's detected position counts its share of an independent
  // observation (correlated detector errors; single-frame mode: once).
  const double position_weight =
      options.detection_position
          ? frame_weight * (single ? 1.0 : CorrelatedObservationShare(num_frames, options.detection_correlation_frames))
          : 0.0;
  int num_points = 0;
  for (int k = 0; k < num_frames; ++k) {
    const TrackFrame& f = track.frames[k];
    double* pose = state->poses[k].data();
    problem->AddParameterBlock(pose, 4);
    num_points += AddDataTerm(lookup, track, k, data[k], sigma_scale, frame_weight, options, state, problem);
    problem->AddResidualBlock(GroundCost::Create(f.ground_plane_in_world, options.sigma_ground, frame_weight),
                              nullptr, pose);
    if (position_weight > 0.0 && f.detection_covariance.determinant() > 0.0) {
      const Eigen::Matrix3d& r = f.world_from_camera.linear();
      ceres::LossFunction* dead_zone =
          options.detection_position_dead_zone > 0.0
              ? new DeadZoneLoss(std::sqrt(position_weight) * options.detection_position_dead_zone)
              : nullptr;
      problem->AddResidualBlock(DetectionPositionCost::Create(f.world_from_camera * f.detection.position,
                                                              r * f.detection_covariance * r.transpose(),
                                                              position_weight, DetectionBiasInWorld(f, options)),
                                dead_zone, pose);
    }
    // One frame (T = 1): no motion term and no velocities; the joint problem
    // is then the single-frame problem.
    if (single || num_frames == 1) continue;
    problem->AddParameterBlock(state->velocities[k].data(), 2);
    if (k == 0) {
      state->models[k] = "none";
      continue;
    }
    AddMotionTerm(track, k, options, frame_weight, state, problem);
  }
  return num_points;
}

double FrameDataCost(const ShapeLookup& lookup, const Track& track, const TrackFrame& f,
                     const Association& association, const Eigen::VectorXd& z, const Eigen::Vector4d& pose,
                     const FitOptions& options) {
  const Association solve = SolveSubsample(association, options.max_solve_points_per_frame);
  const std::unique_ptr<DataCost> cost =
      MakeDataCost(&lookup, solve.points, solve.sigmas, DataTermOptions(track, f, options, 1.0));
  std::vector<double> residuals(solve.points.size());
  cost->EvaluateRows(z.data(), pose.data(), 0, cost->num_residuals(), residuals.data(), nullptr, 0, nullptr, 0);
  double sum = 0.0;
  for (double r : residuals) sum += r * r;
  return sum;
}

}  // namespace samp
