// The tracker's view of a detection and the small geometry its two stages
// share: the online stage (data/tracking.cc) and the offline fragment joining
// and switch resolution (data/track_joining.cc). Internal to the data layer.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "libsamp/core/pose.h"
#include "libsamp/data/track.h"

namespace samp::tracking_internal {

// A detection in the ground plane.
struct Observation {
  int frame = 0;
  double time = 0.0;
  ObjectLabel label;             // as given, frame set
  Eigen::Vector2d ground;        // bottom centre, ground-plane coordinates (e1, e2)
  Eigen::Matrix2d ground_covariance;
  double height = 0.0, height_variance = 0.0;  // along up
  Eigen::Vector3d size;          // h, w, l
  double axis = 0.0;             // heading in the ground plane modulo pi, [0, pi)
};

// Angle difference modulo pi, in [-pi/2, pi/2).
inline double AxisDifference(double a, double b) {
  double d = std::fmod(a - b, kPi);
  if (d < -kPi / 2) d += kPi;
  if (d >= kPi / 2) d -= kPi;
  return d;
}

// Mean axis (modulo pi) of angles: the mean of the doubled-angle unit vectors.
inline double MeanAxis(const std::vector<double>& axes) {
  double c = 0, s = 0;
  for (double a : axes) c += std::cos(2 * a), s += std::sin(2 * a);
  double mean = 0.5 * std::atan2(s, c);
  if (mean < 0) mean += kPi;
  return mean;
}

// White-acceleration process noise of the 2-D constant-velocity model over dt.
inline Eigen::Matrix4d ProcessNoise(double dt, double acceleration_sigma) {
  const double q = acceleration_sigma * acceleration_sigma;
  const double t = std::abs(dt);
  Eigen::Matrix4d noise = Eigen::Matrix4d::Zero();
  noise.topLeftCorner<2, 2>() = q * t * t * t * t / 4.0 * Eigen::Matrix2d::Identity();
  noise.topRightCorner<2, 2>() = q * dt * dt * dt / 2.0 * Eigen::Matrix2d::Identity();
  noise.bottomLeftCorner<2, 2>() = noise.topRightCorner<2, 2>();
  noise.bottomRightCorner<2, 2>() = q * t * t * Eigen::Matrix2d::Identity();
  return noise;
}

inline Eigen::Matrix4d Transition(double dt) {
  Eigen::Matrix4d f = Eigen::Matrix4d::Identity();
  f.topRightCorner<2, 2>() = dt * Eigen::Matrix2d::Identity();
  return f;
}

}  // namespace samp::tracking_internal
