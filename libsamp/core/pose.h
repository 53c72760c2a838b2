// Angles and poses of a car on the road, the one copy every layer uses.
//
// Pose of a car in the world: translation t (origin of the canonical object
// frame = bottom centre of the car; object x front, y down, z left) and yaw
// theta about the world's vertical axis y (KITTI's rotation_y convention):
//   world_from_object = [R_y(theta) | t],  R_y = [[c, 0, s], [0, 1, 0], [-s, 0, c]],
// so the car's heading (object +x) in the world is h(theta) = (cos, 0, -sin).
// Pure functions; thread-safe.
#pragma once

#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace samp {

constexpr double kPi = 3.14159265358979323846;

// Angle wrapped to (-pi, pi].
inline double WrapAngle(double angle) {
  double a = std::remainder(angle, 2.0 * kPi);  // [-pi, pi]
  if (a <= -kPi) a += 2.0 * kPi;
  return a;
}

// Heading of yaw theta in the world: (cos theta, 0, -sin theta).
inline Eigen::Vector3d Heading(double yaw) { return Eigen::Vector3d(std::cos(yaw), 0.0, -std::sin(yaw)); }
// Yaw of a direction (its projection on the x-z plane).
inline double YawOfDirection(const Eigen::Vector3d& d) { return std::atan2(-d.z(), d.x()); }

// world_from_object of pose (t, theta), and its inverse.
inline Eigen::Isometry3d WorldFromObject(const Eigen::Vector3d& translation, double yaw) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  t.translation() = translation;
  return t;
}
inline Eigen::Isometry3d ObjectFromWorld(const Eigen::Vector3d& translation, double yaw) {
  return WorldFromObject(translation, yaw).inverse();
}

}  // namespace samp
