#include "libsamp/fit/initialization.h"

#include <algorithm>
#include <cmath>

#include "libsamp/core/pose.h"
#include "libsamp/core/util.h"

namespace samp {

namespace {

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
  return std::abs(WrapAngle(yaw - reference)) > kPi / 2 ? WrapAngle(yaw + kPi) : WrapAngle(yaw);
}

// Position errors correlated in time as rho^lag (rho = exp(-1 /
// correlation_frames), lag in frame periods: the median time step): the
// variances of the least-squares mean and slope over the frames' times,
// each divided by its value for white errors,
//   mean:  sum_ij rho^lag_ij / n,   slope:  sum_ij w_i w_j rho^lag_ij / sum_i w_i^2,
// w_i = t_i - mean t. Both are 1 for white errors. Correlated errors drift
// together: a white-noise significance overstates a speed (at 3 frames and
// 21 frames the slope's variance is ~5x), and the scatter about the fitted
// line understates the errors (its expected sum of squares is
// sigma^2 (n - mean - slope) instead of sigma^2 (n - 2)).
struct CorrelationFactors {
  double mean = 1.0, slope = 1.0;
};
CorrelationFactors CorrelatedFitFactors(const Track& track, double correlation_frames) {
  const int n = int(track.frames.size());
  CorrelationFactors factors;
  if (correlation_frames <= 0.0 || n < 3) return factors;
  std::vector<double> steps;
  double t_mean = 0.0;
  for (int k = 0; k < n; ++k) {
    t_mean += track.frames[k].time / n;
    if (k > 0) steps.push_back(track.frames[k].time - track.frames[k - 1].time);
  }
  const double period = Median(steps);
  if (!(period > 0.0)) return factors;
  double white = 0.0, mean = 0.0, slope = 0.0;
  for (int i = 0; i < n; ++i) {
    const double wi = track.frames[i].time - t_mean;
    white += wi * wi;
    for (int j = 0; j < n; ++j) {
      const double lag = std::abs(track.frames[i].time - track.frames[j].time) / period;
      const double r = std::exp(-lag / correlation_frames);
      mean += r;
      slope += wi * (track.frames[j].time - t_mean) * r;
    }
  }
  factors.mean = std::max(mean / n, 1.0);
  if (white > 0.0) factors.slope = std::max(slope / white, 1.0);
  return factors;
}

// Velocity on the road by Theil-Sen: per world axis the median over all
// pairs of detections (i < j) of (p_j - p_i) / (t_j - t_i). Unlike the
// median of pairwise speeds (norms, biased upwards by noise) it is ~0 for a
// standing car, and one flipped or displaced detection does not move it.
// *speed_sigma: the standard deviation of its speed (>= 2 frames, else 0),
// for position errors correlated in time as exp(-lag / correlation_frames)
// (0: white).
Eigen::Vector3d TheilSenVelocity(const Track& track, const std::vector<Eigen::Vector3d>& positions,
                                 double correlation_frames, double* speed_sigma) {
  const int num_frames = int(track.frames.size());
  const double t_mean = [&] {
    double sum = 0.0;
    for (const TrackFrame& f : track.frames) sum += f.time;
    return sum / std::max(num_frames, 1);
  }();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  *speed_sigma = 0.0;
  if (num_frames < 2) return velocity;
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
  // for slow, far cars). Both scaled for correlated errors (the scatter's
  // degrees of freedom n - mean - slope instead of n - 2).
  const CorrelationFactors factors = CorrelatedFitFactors(track, correlation_frames);
  const double dof = std::max(num_frames - factors.mean - factors.slope, 1.0);
  const double correlated_scale = std::sqrt(std::max(num_frames - 2, 1) / dof);
  double sum_sq = 0.0;
  for (double r : residuals) sum_sq += r * r;
  const double position_sigma =
      std::max(1.4826 * Median(residuals) * correlated_scale, std::sqrt(sum_sq / dof));
  *speed_sigma = position_sigma / std::sqrt(std::max(spread, 1e-12)) * std::sqrt(factors.slope);
  return velocity;
}

// The detections' orientation: axis by the doubled-angle mean, direction by
// the majority of detections.
double DetectedYaw(const std::vector<double>& detection_yaws) {
  double sx = 0, sy = 0;
  for (double y : detection_yaws) {
    sx += std::cos(2 * y);
    sy += std::sin(2 * y);
  }
  double detected_yaw = 0.5 * std::atan2(sy, sx);
  int agree = 0;
  for (double y : detection_yaws) agree += std::abs(WrapAngle(y - detected_yaw)) <= kPi / 2 ? 1 : -1;
  if (agree < 0) detected_yaw = WrapAngle(detected_yaw + kPi);
  return detected_yaw;
}

// Median over all pairs of frames (i < j) of the change of the aligned yaws per second.
double MedianYawRate(const Track& track, const std::vector<double>& aligned) {
  const int num_frames = int(track.frames.size());
  std::vector<double> rates;
  for (int i = 0; i < num_frames; ++i) {
    for (int j = i + 1; j < num_frames; ++j) {
      const double dt = track.frames[j].time - track.frames[i].time;
      rates.push_back(WrapAngle(aligned[j] - aligned[i]) / dt);
    }
  }
  return Median(rates);
}

}  // namespace

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
  double velocity_sigma = 0.0;  // of the speed, m/s
  const Eigen::Vector3d velocity = TheilSenVelocity(track, positions, options.detection_correlation_frames, &velocity_sigma);
  const double speed = velocity.norm();
  const double detected_yaw = DetectedYaw(detection_yaws);
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
    if (std::min(off_axis, kPi - off_axis) > options.max_motion_off_axis) {
      init.standing = true;
    } else {
      reference = motion_yaw;
    }
  }
  std::vector<double> aligned(num_frames);
  for (int k = 0; k < num_frames; ++k) aligned[k] = AlignYaw(detection_yaws[k], reference);
  const double yaw_rate = init.standing ? 0.0 : MedianYawRate(track, aligned);
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

}  // namespace samp
