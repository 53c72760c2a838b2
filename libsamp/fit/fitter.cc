#include "libsamp/fit/fitter.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/core/util.h"
#include "libsamp/fit/detection_position_cost.h"
#include "libsamp/fit/detection_size_cost.h"
#include "libsamp/fit/ground_cost.h"
#include "libsamp/fit/motion_cost.h"
#include "libsamp/fit/sdf_cost.h"
#include "libsamp/fit/shape_prior_cost.h"

namespace samp {

namespace {

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}


std::string Upper(std::string s) {
  for (char& c : s) c = char(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// Bottom centre of the detection projected onto the road plane (world).
Eigen::Vector3d DetectionOnGround(const TrackFrame& f) {
  const Eigen::Vector3d p = f.world_from_camera * f.detection.position;
  const Eigen::Vector3d n = f.ground_plane_in_world.head<3>();
  return p - (n.dot(p) + f.ground_plane_in_world[3]) * n;
}

double DetectionYaw(const TrackFrame& f) {
  return YawOfDirection(f.world_from_camera.linear() * Heading(f.detection.rotation_y));
}

// Yaw flipped by pi when it points away (more than 90 degrees) from `reference`.
double AlignYaw(double yaw, double reference) {
  return std::abs(WrapAngle(yaw - reference)) > M_PI / 2 ? WrapAngle(yaw + M_PI) : WrapAngle(yaw);
}

// Data of one frame: the associated points and their sigmas.
struct Association {
  std::vector<Eigen::Vector3d> points;
  std::vector<double> sigmas;
};

// Initial association around the detection's box centre. kPaper /
// kRayDepth: within `radius` (a sphere). kDisparity: the point's viewing ray
// passes within `radius` of the centre and its distance along the ray lies
// within radius + 3 sigma (sigma along the ray) of the centre's: a sphere
// would cut the stereo noise of far cars (sigma of metres along the ray)
// unevenly about a detection that is itself off along the ray, and bias the
// fit.
Association AssociateByDetection(const TrackFrame& f, double radius, DataTerm term) {
  Association a;
  const Eigen::Vector3d centre =
      f.world_from_camera *
      (f.detection.position - Eigen::Vector3d(0.0, 0.5 * f.detection.height, 0.0));
  const Eigen::Vector3d camera = f.world_from_camera.translation();
  const Eigen::Vector3d axis = f.world_from_camera.linear().col(2);
  for (size_t i = 0; i < f.candidate_points_in_world.size(); ++i) {
    const Eigen::Vector3d& p = f.candidate_points_in_world[i];
    bool keep;
    if (term == DataTerm::kDisparity) {
      const Eigen::Vector3d ray = p - camera;
      const double length = ray.norm();
      const Eigen::Vector3d u = ray / length;
      const double along = (centre - camera).dot(u);
      const double lateral = ((centre - camera) - along * u).norm();
      // The noise at the centre's depth (sigma_d grows with z^2: the
      // point's own sigma would let far background pass).
      const double depth_ratio = (centre - camera).dot(axis) / std::max(ray.dot(axis), 1e-3);
      const double sigma_along = f.candidate_sigmas[i] * depth_ratio * depth_ratio / std::max(u.dot(axis), 1e-3);
      keep = lateral <= radius && std::abs(length - along) <= radius + 3.0 * sigma_along;
    } else {
      keep = (p - centre).norm() <= radius;
    }
    if (keep) {
      a.points.push_back(p);
      a.sigmas.push_back(f.candidate_sigmas[i]);
    }
  }
  return a;
}

Association AssociateByFit(const TrackFrame& f, const ShapeLookup& lookup, const Eigen::VectorXd& z,
                           const Eigen::Vector4d& pose, const AlignedBox& box,
                           const FitOptions& options, std::string* why) {
  Association a;
  int outside_box = 0, too_far = 0;
  const Eigen::Isometry3d object_from_world = ObjectFromWorld(pose.head<3>(), pose[3]);
  const Eigen::Vector3d lo = box.min - Eigen::Vector3d::Constant(options.em_box_margin);
  const Eigen::Vector3d hi = box.max + Eigen::Vector3d::Constant(options.em_box_margin);
  for (size_t i = 0; i < f.candidate_points_in_world.size(); ++i) {
    const Eigen::Vector3d o = object_from_world * f.candidate_points_in_world[i];
    if ((o.array() < lo.array()).any() || (o.array() > hi.array()).any()) {
      ++outside_box;
      continue;
    }
    if (std::abs(lookup.Evaluate(z.data(), o.data(), nullptr, nullptr)) >= options.em_distance_threshold) {
      ++too_far;
      continue;
    }
    a.points.push_back(f.candidate_points_in_world[i]);
    a.sigmas.push_back(f.candidate_sigmas[i]);
  }
  std::ostringstream s;
  s << a.points.size() << " of " << f.candidate_points_in_world.size() << " candidates kept; " << outside_box
    << " outside the fitted box + " << options.em_box_margin << " m, " << too_far << " with |phi| >= "
    << options.em_distance_threshold << " m";
  *why = s.str();
  return a;
}

SdfCostOptions DataTermOptions(const Track& track, const TrackFrame& f, const FitOptions& options, double weight);

// EM association of the disparity term: the candidates whose residual at the
// fitted shape and pose is an inlier of the mixture (|s_i| below the
// outlier threshold): on a ray that meets the shape, a disparity within s_0
// sigma of the visible surface's; on a ray that misses it, within s_0
// silhouette sigmas of the silhouette. *why says how many were dropped and why.
Association AssociateByResiduals(const Track& track, const TrackFrame& f, const ShapeLookup& lookup,
                                 const Eigen::VectorXd& z, const Eigen::Vector4d& pose, const FitOptions& options,
                                 std::string* why) {
  Association a;
  std::ostringstream s;
  if (f.candidate_points_in_world.empty()) {
    *why = "no candidate points (none inside the detection's 2D box above the road)";
    return a;
  }
  const SdfCost cost(&lookup, f.candidate_points_in_world, f.candidate_sigmas,
                     DataTermOptions(track, f, options, 1.0));
  const std::vector<RayResidual> residuals = cost.RayResiduals(z.data(), pose.data());
  int in_front = 0, behind = 0, missing = 0;
  for (size_t i = 0; i < residuals.size(); ++i) {
    const RayResidual& r = residuals[i];
    if (std::abs(r.value) < options.outlier_threshold) {
      a.points.push_back(f.candidate_points_in_world[i]);
      a.sigmas.push_back(f.candidate_sigmas[i]);
    } else if (!r.hit) {
      ++missing;
    } else if (r.value > 0.0) {
      ++in_front;
    } else {
      ++behind;
    }
  }
  s << a.points.size() << " of " << residuals.size() << " candidates kept; " << in_front
    << " in front of the fitted surface, " << behind << " behind it (by > " << options.outlier_threshold
    << " sigma_disp), " << missing << " on rays missing the shape by > " << options.outlier_threshold
    << " silhouette sigmas";
  *why = s.str();
  return a;
}

void CheckTrack(const Track& track) {
  const std::string name = "track " + std::to_string(track.id) +
                           (track.sequence.empty() ? "" : " of sequence " + track.sequence);
  SAMP_CHECK(!track.frames.empty()) << name << " has no frames";
  for (size_t k = 0; k < track.frames.size(); ++k) {
    const TrackFrame& f = track.frames[k];
    SAMP_CHECK(f.candidate_points_in_world.size() == f.candidate_sigmas.size())
        << name << " frame " << f.frame << ": " << f.candidate_points_in_world.size()
        << " points but " << f.candidate_sigmas.size() << " sigmas";
    SAMP_CHECK(std::isfinite(f.time)) << name << " frame " << f.frame << ": time is not finite";
    SAMP_CHECK(f.detection.position.allFinite() && std::isfinite(f.detection.rotation_y))
        << name << " frame " << f.frame << ": detection is not finite";
    SAMP_CHECK(f.world_from_camera.matrix().allFinite())
        << name << " frame " << f.frame << ": ego pose is not finite";
    SAMP_CHECK(f.ground_plane_in_world.allFinite() &&
               std::abs(f.ground_plane_in_world.head<3>().norm() - 1.0) < 1e-3)
        << name << " frame " << f.frame << ": ground plane must be finite with a unit normal";
    for (size_t i = 0; i < f.candidate_points_in_world.size(); ++i) {
      SAMP_CHECK(f.candidate_points_in_world[i].allFinite() && f.candidate_sigmas[i] > 0.0 &&
                 std::isfinite(f.candidate_sigmas[i]))
          << name << " frame " << f.frame << ": point " << i << " or its sigma is invalid";
    }
    if (k > 0) {
      SAMP_CHECK(f.time > track.frames[k - 1].time)
          << name << ": frame times must increase (frame " << f.frame << ")";
    }
  }
}

}  // namespace

const char* DataWeightingName(DataWeighting weighting) {
  return weighting == DataWeighting::kMean ? "mean" : "effective";
}

DataWeighting ParseDataWeighting(const std::string& name) {
  if (name == "mean") return DataWeighting::kMean;
  if (name == "effective") return DataWeighting::kEffective;
  SAMP_THROW() << "unknown data weighting '" << name << "' (mean, effective)";
}

std::string FitSummary::BriefReport() const {
  std::ostringstream s;
  s << solves.size() << " solve(s), " << num_iterations << " LM iterations, cost "
    << initial_cost << " -> " << final_cost << ", " << seconds * 1e3 << " ms"
    << (usable ? "" : " [NOT USABLE]");
  if (!solves.empty()) s << ", last: " << solves.back().termination;
  return s.str();
}

std::string FitSummary::UnusableReason() const {
  if (solves.empty()) return "no solve was run";
  for (size_t k = 0; k < solves.size(); ++k) {
    if (solves[k].usable) continue;
    std::ostringstream s;
    s << "solve " << k + 1 << " of " << solves.size() << (k == 0 ? " (initial)" : " (EM)")
      << " is not usable: " << (solves[k].termination.empty() ? "no termination reported" : solves[k].termination);
    return s.str();
  }
  return "";
}

Eigen::Isometry3d FrameFit::WorldFromObject() const { return samp::WorldFromObject(position, yaw); }

InitialState InitializeTrack(const Track& track, const FitOptions& options) {
  const int num_frames = int(track.frames.size());
  InitialState init;
  init.poses.resize(num_frames);
  init.velocities.assign(num_frames, Eigen::Vector2d::Zero());
  std::vector<Eigen::Vector3d> positions(num_frames);
  std::vector<double> detection_yaws(num_frames);
  for (int k = 0; k < num_frames; ++k) {
    positions[k] = DetectionOnGround(track.frames[k]);
    detection_yaws[k] = DetectionYaw(track.frames[k]);
  }
  // Velocity on the road by Theil-Sen: per world axis the median over all
  // pairs of detections (i < j) of (p_j - p_i) / (t_j - t_i). Unlike the
  // median of pairwise speeds (norms, biased upwards by noise) it is ~0 for a
  // standing car, and one flipped or displaced detection does not move it.
  const double t_mean = [&] {
    double sum = 0.0;
    for (const TrackFrame& f : track.frames) sum += f.time;
    return sum / std::max(num_frames, 1);
  }();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  double velocity_sigma = 0.0;  // of the speed, m/s
  if (num_frames >= 2) {
    std::vector<double> slopes[3], offsets[3];
    for (int i = 0; i < num_frames; ++i) {
      for (int j = i + 1; j < num_frames; ++j) {
        const double dt = track.frames[j].time - track.frames[i].time;
        for (int a = 0; a < 3; ++a) slopes[a].push_back((positions[j][a] - positions[i][a]) / dt);
      }
    }
    for (int a = 0; a < 3; ++a) velocity[a] = Median(slopes[a]);
    const Eigen::Vector3d n = track.frames.front().ground_plane_in_world.head<3>();
    velocity -= n.dot(velocity) * n;  // along the road
    // Noise of the positions about the fitted line along the velocity,
    // propagated to the slope as for least squares.
    std::vector<double> residuals;
    for (int a = 0; a < 3; ++a) {
      for (int k = 0; k < num_frames; ++k) offsets[a].push_back(positions[k][a] - velocity[a] * track.frames[k].time);
    }
    Eigen::Vector3d offset;
    for (int a = 0; a < 3; ++a) offset[a] = Median(offsets[a]);
    double spread = 0.0;
    for (int k = 0; k < num_frames; ++k) {
      // Along the velocity: the noise that could fake this speed (the
      // detections' scatter is anisotropic, mostly along the line of sight).
      const Eigen::Vector3d r = positions[k] - offset - velocity * track.frames[k].time;
      const double speed_so_far = velocity.norm();
      residuals.push_back(speed_so_far > 0.0 ? std::abs(r.dot(velocity) / speed_so_far)
                                             : (r - n.dot(r) * n).norm() / std::sqrt(2.0));
      spread += (track.frames[k].time - t_mean) * (track.frames[k].time - t_mean);
    }
    // The larger of a robust (1.4826 MAD) and the plain RMS estimate: with ~20
    // frames either alone is often low by a third, and too low a noise makes
    // scatter look like motion (erring the other way only delays "moving"
    // for slow, far cars).
    double sum_sq = 0.0;
    for (double r : residuals) sum_sq += r * r;
    const double position_sigma =
        std::max(1.4826 * Median(residuals), std::sqrt(sum_sq / std::max(num_frames - 2, 1)));
    velocity_sigma = position_sigma / std::sqrt(std::max(spread, 1e-12));
  }
  const double speed = velocity.norm();
  // The detections' orientation: axis by the doubled-angle mean, direction by
  // the majority of detections.
  double detected_yaw;
  {
    double sx = 0, sy = 0;
    for (double y : detection_yaws) {
      sx += std::cos(2 * y);
      sy += std::sin(2 * y);
    }
    detected_yaw = 0.5 * std::atan2(sy, sx);
    int agree = 0;
    for (double y : detection_yaws) agree += std::abs(WrapAngle(y - detected_yaw)) <= M_PI / 2 ? 1 : -1;
    if (agree < 0) detected_yaw = WrapAngle(detected_yaw + M_PI);
  }
  // Standing when slow, or when the speed is within the noise of its estimate
  // (far cars: at 40 m the detections scatter by metres along the line of
  // sight, and the direction of that scatter would give a standing car a
  // random heading).
  init.standing = num_frames < 2 || speed < options.standing_speed ||
                  speed < options.min_speed_significance * velocity_sigma;
  double reference = detected_yaw;
  if (!init.standing) {
    // A car drives along its length axis: a velocity far off the detected
    // axis is detection noise on a standing car, not motion.
    const double motion_yaw = YawOfDirection(velocity);
    const double off_axis = std::abs(WrapAngle(motion_yaw - detected_yaw));
    if (std::min(off_axis, M_PI - off_axis) > options.max_motion_off_axis) {
      init.standing = true;
    } else {
      reference = motion_yaw;
    }
  }
  std::vector<double> aligned(num_frames);
  for (int k = 0; k < num_frames; ++k) aligned[k] = AlignYaw(detection_yaws[k], reference);
  double yaw_rate = 0.0;
  if (!init.standing) {
    std::vector<double> rates;
    for (int i = 0; i < num_frames; ++i) {
      for (int j = i + 1; j < num_frames; ++j) {
        const double dt = track.frames[j].time - track.frames[i].time;
        rates.push_back(WrapAngle(aligned[j] - aligned[i]) / dt);
      }
    }
    yaw_rate = Median(rates);
  }
  // Moving: on a circular arc the chord's direction is the heading at the
  // middle time, so yaw_k = segment yaw + omega (time_k - middle time).
  const double middle = 0.5 * (track.frames.front().time + track.frames.back().time);
  for (int k = 0; k < num_frames; ++k) {
    const double yaw =
        init.standing ? aligned[k] : WrapAngle(reference + yaw_rate * (track.frames[k].time - middle));
    init.poses[k] << positions[k], yaw;
    init.velocities[k] = init.standing ? Eigen::Vector2d::Zero() : Eigen::Vector2d(speed, yaw_rate);
  }
  return init;
}

TrackFitter::TrackFitter(const ShapeModel& model, const FitOptions& options)
    : lookup_(model), options_(options) {
  options_.Check();
}

namespace {

struct FitState {
  std::vector<Eigen::VectorXd> codes;  // 1 (joint) or T (single frame)
  std::vector<Eigen::Vector4d> poses;
  std::vector<Eigen::Vector2d> velocities;
  std::vector<std::string> models;
};

// Ends a solve after this many consecutive rejected LM steps: the cost sits
// at a kink of the residuals (with the ray-distance data term, rays that
// switch between meeting and missing the surface make the cost jump by
// ~1e-3 for any step), where shrinking the trust region gains nothing.
class StopAfterRejectedSteps : public ceres::IterationCallback {
 public:
  explicit StopAfterRejectedSteps(int max_rejected) : max_rejected_(max_rejected) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    rejected_ = summary.iteration > 0 && !summary.step_is_successful ? rejected_ + 1 : 0;
    return rejected_ >= max_rejected_ ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }

 private:
  int max_rejected_;
  int rejected_ = 0;
};

SdfCostOptions DataTermOptions(const Track& track, const TrackFrame& f, const FitOptions& options, double weight) {
  SdfCostOptions o;
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

// Effective number of independent observations of a frame's n associated
// points (docs/fitting.md, "Prior/data balance").
double EffectivePoints(const TrackFrame& f, int n, const FitOptions& options) {
  if (options.data_weighting == DataWeighting::kMean) return double(n);
  return std::min(double(n), n * f.candidate_pixels_per_point / options.correlation_area_px);
}

// The points of a frame's association that enter a solve: all of them, or
// `max_points` spread evenly over the association's order (k = floor((j +
// 1/2) n / max_points)); deterministic.
void SolveSubsample(const Association& a, int max_points, std::vector<Eigen::Vector3d>* points,
                    std::vector<double>* sigmas) {
  const size_t n = a.points.size();
  if (max_points <= 0 || n <= size_t(max_points)) {
    *points = a.points;
    *sigmas = a.sigmas;
    return;
  }
  points->resize(size_t(max_points));
  sigmas->resize(size_t(max_points));
  for (size_t j = 0; j < size_t(max_points); ++j) {
    const size_t k = std::min(n - 1, size_t((double(j) + 0.5) * double(n) / double(max_points)));
    (*points)[j] = a.points[k];
    (*sigmas)[j] = a.sigmas[k];
  }
}

// The share of T observations with AR(1)-correlated errors (correlation
// exp(-1 / tau) between neighbours) that their mean counts as independent:
// N_eff / T = T / sum_ij rho^|i - j| (1 for T = 1 or tau = 0; -> (1 - rho) / (1 + rho)).
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

// The detected box sizes as observations of each code (detection_size_cost.h),
// the inside box's size linearised about the code the solve starts from.
// Joint mode: every frame's detection observes the one code, each counting
// CorrelatedObservationShare of an observation (correlated detector errors); single-frame
// mode: each frame's code its own detection, once.
void AddDetectionSizeTerms(const ShapeLookup& lookup, const Track& track, const FitOptions& options,
                           double frame_weight, FitState* state, ceres::Problem* problem) {
  if (options.detection_size_sigma <= 0.0) return;
  const bool single = options.single_frame;
  const double per_frame =
      frame_weight * (single ? 1.0 : CorrelatedObservationShare(int(track.frames.size()),
                                                                options.detection_correlation_frames));
  // Half a sigma: wide enough to smooth the box's voxel kinks, narrow enough to stay local.
  constexpr double kStep = 0.5;
  // Single-frame codes that are equal (all of them in the first solve, from
  // the mean) share one linearisation: 2R + 1 box evaluations each.
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
                                                          options.detection_size_sigma, per_frame),
                                nullptr, state->codes[c].data());
    }
  }
}

SolveReport Solve(const ShapeLookup& lookup, const Track& track,
                  const std::vector<Association>& data, double sigma_scale,
                  const FitOptions& options, FitState* state) {
  const int num_frames = int(track.frames.size());
  const bool single = options.single_frame;
  // kMean: the paper's E = (1/T) sum_t [E_data,t (a mean over points) + ...] + E_shape;
  // kEffective: the negative log-posterior, every frame and point counted.
  const bool mean = options.data_weighting == DataWeighting::kMean;
  const double frame_weight = mean ? 1.0 / num_frames : 1.0;
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  SolveReport report;
  for (int c = 0; c < int(state->codes.size()); ++c) {
    problem.AddParameterBlock(state->codes[c].data(), lookup.num_components());
    if (options.shape_prior_weight > 0.0) {
      problem.AddResidualBlock(
          ShapePriorCost::Create(lookup.sigmas(), options.shape_prior_weight * (single ? frame_weight : 1.0)),
          nullptr, state->codes[c].data());
    }
  }
  AddDetectionSizeTerms(lookup, track, options, frame_weight, state, &problem);
  // Each frame's detected position counts its share of an independent
  // observation (correlated detector errors; single-frame mode: once).
  const double position_weight =
      options.detection_position
          ? frame_weight * (single ? 1.0 : CorrelatedObservationShare(num_frames, options.detection_correlation_frames))
          : 0.0;
  for (int k = 0; k < num_frames; ++k) {
    const TrackFrame& f = track.frames[k];
    double* z = state->codes[single ? k : 0].data();
    double* pose = state->poses[k].data();
    problem.AddParameterBlock(pose, 4);
    if (int(data[k].points.size()) >= options.min_points_per_frame) {
      const int n = int(data[k].points.size());
      const double data_weight = mean ? frame_weight : EffectivePoints(f, n, options);
      const SdfCostOptions cost_options = DataTermOptions(track, f, options, data_weight);
      std::vector<Eigen::Vector3d> points;
      std::vector<double> sigmas;
      SolveSubsample(data[k], options.max_solve_points_per_frame, &points, &sigmas);
      for (double& s : sigmas) s *= sigma_scale;
      ceres::CostFunction* cost =
          options.compress_data_blocks ? CompressedSdfCost::Create(&lookup, points, sigmas, cost_options)
                                       : SdfCost::Create(&lookup, points, sigmas, cost_options);
      problem.AddResidualBlock(cost, nullptr, z, pose);
      report.num_points += int(points.size());
    }
    problem.AddResidualBlock(GroundCost::Create(f.ground_plane_in_world, options.sigma_ground, frame_weight),
                             nullptr, pose);
    if (position_weight > 0.0 && f.detection_covariance.determinant() > 0.0) {
      const Eigen::Matrix3d& r = f.world_from_camera.linear();
      problem.AddResidualBlock(DetectionPositionCost::Create(f.world_from_camera * f.detection.position,
                                                             r * f.detection_covariance * r.transpose(),
                                                             position_weight),
                               nullptr, pose);
    }
    // One frame (T = 1): no motion term and no velocities; the joint problem
    // is then the single-frame problem.
    if (single || num_frames == 1) continue;
    problem.AddParameterBlock(state->velocities[k].data(), 2);
    if (k == 0) {
      state->models[k] = "none";
      continue;
    }
    const double dt = f.time - track.frames[k - 1].time;
    double* prev_pose = state->poses[k - 1].data();
    double* prev_vel = state->velocities[k - 1].data();
    const MotionModel model = SelectMotionModel(prev_vel[0], prev_vel[1], options.standing_speed,
                                                options.straight_yaw_rate);
    state->models[k] = MotionModelName(model);
    const auto sigma = MotionCovariance(model, prev_pose, prev_vel, dt, options.motion_noise);
    problem.AddResidualBlock(MotionCost::Create(model, dt, SqrtInformation(sigma), frame_weight), nullptr,
                             prev_pose, prev_vel, pose, state->velocities[k].data());
  }
  ceres::Solver::Options solver_options;
  solver_options.minimizer_type = ceres::TRUST_REGION;
  solver_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  SAMP_CHECK(ceres::StringToLinearSolverType(Upper(options.linear_solver), &solver_options.linear_solver_type))
      << "unknown linear solver " << options.linear_solver;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = options.function_tolerance;
  solver_options.gradient_tolerance = options.gradient_tolerance;
  solver_options.parameter_tolerance = options.parameter_tolerance;
  solver_options.num_threads = options.num_threads;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  StopAfterRejectedSteps stop(options.max_rejected_steps);
  if (options.max_rejected_steps > 0) solver_options.callbacks.push_back(&stop);
  ceres::Solver::Summary summary;
  const auto start = std::chrono::steady_clock::now();
  ceres::Solve(solver_options, &problem, &summary);
  report.seconds = Seconds(start);
  report.initial_cost = summary.initial_cost;
  report.final_cost = summary.final_cost;
  report.num_iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  std::vector<double> step_seconds;  // iterations[0] is the initial evaluation, not a step
  for (size_t k = 1; k < summary.iterations.size(); ++k) {
    step_seconds.push_back(summary.iterations[k].iteration_time_in_seconds);
  }
  report.median_step_seconds = Median(step_seconds);
  report.usable = summary.IsSolutionUsable();
  report.termination = std::string(ceres::TerminationTypeToString(summary.termination_type)) + ": " +
                       summary.message;
  for (auto& pose : state->poses) pose[3] = WrapAngle(pose[3]);
  return report;
}

}  // namespace

TrackFit TrackFitter::Fit(const Track& track) const {
  const auto start = std::chrono::steady_clock::now();
  CheckTrack(track);
  const std::string name = "track " + std::to_string(track.id) +
                           (track.sequence.empty() ? "" : " of sequence " + track.sequence);
  const int num_frames = int(track.frames.size());
  const int nr = lookup_.num_components();
  const bool single = options_.single_frame;

  const InitialState init = InitializeTrack(track, options_);
  FitState state;
  state.codes.assign(single ? num_frames : 1, Eigen::VectorXd::Zero(nr));
  state.poses = init.poses;
  state.velocities = init.velocities;
  state.models.assign(num_frames, "none");

  std::vector<Association> data(num_frames);
  int frames_with_data = 0;
  for (int k = 0; k < num_frames; ++k) {
    data[k] = AssociateByDetection(track.frames[k], options_.association_radius, options_.data_term);
    frames_with_data += int(data[k].points.size()) >= options_.min_points_per_frame;
  }
  SAMP_CHECK(frames_with_data > 0) << name << " has no frame with >= " << options_.min_points_per_frame
                                   << " stereo points within " << options_.association_radius
                                   << " m of the detection";

  TrackFit fit;
  fit.track_id = track.id;
  fit.sequence = track.sequence;
  fit.type = track.type;
  fit.single_frame = single;
  const double first_scale = options_.em_iterations > 0 ? options_.em_initial_sigma_scale : 1.0;
  fit.summary.solves.push_back(Solve(lookup_, track, data, first_scale, options_, &state));
  for (int it = 0; it < options_.em_iterations; ++it) {
    // Re-associate with the fitted shape and trajectory.
    std::vector<AlignedBox> boxes(state.codes.size());
    for (size_t c = 0; c < state.codes.size(); ++c) boxes[c] = lookup_.InsideBox(state.codes[c]);
    std::vector<Association> refined(num_frames);
    std::vector<std::string> notes;
    int refined_frames = 0;
    for (int k = 0; k < num_frames; ++k) {
      const int c = single ? k : 0;
      std::string why;
      if (options_.data_term == DataTerm::kDisparity) {
        refined[k] = AssociateByResiduals(track, track.frames[k], lookup_, state.codes[c], state.poses[k],
                                          options_, &why);
      } else if (boxes[c].IsEmpty()) {
        why = "the fitted shape is empty (phi_z >= 0 everywhere)";
      } else {
        refined[k] =
            AssociateByFit(track.frames[k], lookup_, state.codes[c], state.poses[k], boxes[c], options_, &why);
      }
      if (int(refined[k].points.size()) >= options_.min_points_per_frame) {
        ++refined_frames;
      } else {
        notes.push_back("frame " + std::to_string(track.frames[k].frame) + ": " + why);
      }
    }
    fit.summary.association_notes.insert(fit.summary.association_notes.end(), notes.begin(), notes.end());
    if (refined_frames == 0) {
      std::ostringstream message;
      message << name << ": EM association kept fewer than " << options_.min_points_per_frame
              << " points in every frame; keeping the detection association. Per frame:";
      for (const std::string& note : notes) message << "\n  " << note;
      LogWarning() << message.str();
      break;
    }
    if (!notes.empty()) {
      LogInfo() << name << ": EM association: " << notes.size() << " of " << num_frames
                << " frame(s) without data term (first: " << notes.front() << ")";
    }
    data = std::move(refined);
    fit.summary.solves.push_back(Solve(lookup_, track, data, 1.0, options_, &state));
  }

  // Diverged frames back to their initial pose.
  std::vector<int> reset_frames;
  for (int k = 0; k < num_frames; ++k) {
    if ((state.poses[k].head<3>() - init.poses[k].head<3>()).norm() <= options_.max_position_change) continue;
    state.poses[k] = init.poses[k];
    if (single) state.codes[k].setZero();
    reset_frames.push_back(track.frames[k].frame);
  }
  fit.summary.num_frames_reset = int(reset_frames.size());
  if (!reset_frames.empty()) {
    std::ostringstream list;
    for (int f : reset_frames) list << " " << f;
    LogWarning() << name << ": " << reset_frames.size() << " frame(s) moved more than "
                 << options_.max_position_change << " m from the detection and were reset to it:" << list.str();
  }

  // Results.
  fit.summary.initial_cost = fit.summary.solves.front().initial_cost;
  fit.summary.final_cost = fit.summary.solves.back().final_cost;
  fit.summary.usable = true;
  for (const SolveReport& s : fit.summary.solves) {
    fit.summary.num_iterations += s.num_iterations;
    fit.summary.usable = fit.summary.usable && s.usable;
  }
  if (single) {
    fit.shape_code = Eigen::VectorXd::Zero(nr);
    for (const auto& z : state.codes) fit.shape_code += z / double(num_frames);
  } else {
    fit.shape_code = state.codes[0];
  }
  fit.frames.resize(num_frames);
  for (int k = 0; k < num_frames; ++k) {
    FrameFit& out = fit.frames[k];
    const TrackFrame& f = track.frames[k];
    out.frame = f.frame;
    out.time = f.time;
    out.position = state.poses[k].head<3>();
    out.yaw = WrapAngle(state.poses[k][3]);
    out.motion_model = state.models[k];
    out.num_points = int(data[k].points.size()) >= options_.min_points_per_frame ? int(data[k].points.size()) : 0;
    const Eigen::VectorXd& z = state.codes[single ? k : 0];
    if (single) out.shape_code = z;
    if (!single) {
      out.speed = state.velocities[k][0];
      out.yaw_rate = state.velocities[k][1];
    }
    if (out.num_points > 0) {
      // The data term as optimised (weight 1: the mean of rho over the
      // points of the last solve, the subsample when the frame was capped).
      out.effective_points = EffectivePoints(f, out.num_points, options_);
      std::vector<Eigen::Vector3d> points;
      std::vector<double> sigmas;
      SolveSubsample(data[k], options_.max_solve_points_per_frame, &points, &sigmas);
      const SdfCost cost(&lookup_, points, sigmas, DataTermOptions(track, f, options_, 1.0));
      std::vector<double> residuals(points.size());
      cost.EvaluateRows(z.data(), state.poses[k].data(), 0, cost.num_residuals(), residuals.data(), nullptr, 0,
                        nullptr, 0);
      double sum = 0.0;
      for (double r : residuals) sum += r * r;
      out.data_cost = sum;
      if (options_.keep_points) out.points_in_world = data[k].points;
    }
  }
  if (single) {
    // Velocities by finite differences of the fitted poses (reported only).
    for (int k = 0; k < num_frames; ++k) {
      const int a = std::max(0, k - 1), b = std::min(num_frames - 1, std::max(k, a + 1));
      if (a == b) continue;
      const double dt = fit.frames[b].time - fit.frames[a].time;
      fit.frames[k].speed = (fit.frames[b].position - fit.frames[a].position).norm() / dt;
      fit.frames[k].yaw_rate = WrapAngle(fit.frames[b].yaw - fit.frames[a].yaw) / dt;
    }
  }
  fit.summary.seconds = Seconds(start);
  if (!fit.summary.usable) LogWarning() << name << ": solver result not usable: " << fit.summary.BriefReport();
  return fit;
}

}  // namespace samp
