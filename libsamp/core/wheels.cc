#include "libsamp/core/wheels.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "libsamp/core/error.h"

namespace samp {

void WheelOptions::Check() const {
  auto positive_or_zero = [](double v) { return std::isfinite(v) && v >= 0.0; };
  SAMP_CHECK(positive_or_zero(radius)) << "wheels: radius must be >= 0 (0 = auto), got " << radius;
  SAMP_CHECK(std::isfinite(radius_per_length) && radius_per_length > 0.0)
      << "wheels: radius_per_length must be > 0, got " << radius_per_length;
  SAMP_CHECK(std::isfinite(min_radius) && min_radius > 0.0 && std::isfinite(max_radius) &&
             max_radius >= min_radius)
      << "wheels: need 0 < min_radius <= max_radius, got " << min_radius << ", " << max_radius;
  SAMP_CHECK(positive_or_zero(width)) << "wheels: width must be >= 0 (0 = auto), got " << width;
  SAMP_CHECK(std::isfinite(width_per_radius) && width_per_radius > 0.0)
      << "wheels: width_per_radius must be > 0, got " << width_per_radius;
  SAMP_CHECK(std::isfinite(wheelbase_per_length) && wheelbase_per_length > 0.0 &&
             wheelbase_per_length < 1.0)
      << "wheels: wheelbase_per_length must be in (0, 1), got " << wheelbase_per_length;
  SAMP_CHECK(std::isfinite(axle_centre_offset_per_length) &&
             std::abs(axle_centre_offset_per_length) + 0.5 * wheelbase_per_length < 0.5)
      << "wheels: axle_centre_offset_per_length " << axle_centre_offset_per_length
      << " puts an axle outside the body (|offset| + wheelbase_per_length / 2 must be < 0.5)";
  SAMP_CHECK(positive_or_zero(side_inset)) << "wheels: side_inset must be >= 0, got " << side_inset;
  SAMP_CHECK(positive_or_zero(ground_clearance))
      << "wheels: ground_clearance must be >= 0, got " << ground_clearance;
  SAMP_CHECK(segments >= 8) << "wheels: segments must be >= 8, got " << segments;
}

std::string WheelPlacement::BriefReport() const {
  std::ostringstream s;
  s.precision(3);
  s << "wheels: radius " << radius << " m, width " << width << " m, wheelbase "
    << (centers[0].x() - centers[2].x()) << " m, track " << (centers[0].z() - centers[1].z())
    << " m, body lifted by " << lift << " m";
  return s.str();
}

Mesh WheeledCar::Combined() const {
  Mesh mesh = body;
  mesh.Append(wheels);
  return mesh;
}

Mesh MakeWheelMesh(const Eigen::Vector3d& center, double radius, double width, int segments) {
  SAMP_CHECK(radius > 0.0 && width > 0.0 && segments >= 3)
      << "MakeWheelMesh: need radius > 0, width > 0, segments >= 3";
  Mesh mesh;
  const double half = 0.5 * width;
  // Ring vertices: 2 * s at z = -half, 2 * s + 1 at z = +half; then the two cap centres.
  for (int s = 0; s < segments; ++s) {
    const double phi = 2.0 * M_PI * s / segments;
    const double x = center.x() + radius * std::cos(phi), y = center.y() + radius * std::sin(phi);
    mesh.vertices.emplace_back(float(x), float(y), float(center.z() - half));
    mesh.vertices.emplace_back(float(x), float(y), float(center.z() + half));
  }
  const int back = 2 * segments, front = back + 1;
  mesh.vertices.emplace_back(center.cast<float>() - Eigen::Vector3f(0, 0, float(half)));
  mesh.vertices.emplace_back(center.cast<float>() + Eigen::Vector3f(0, 0, float(half)));
  for (int s = 0; s < segments; ++s) {
    const int n = (s + 1) % segments;
    const int a0 = 2 * s, a1 = 2 * s + 1, b0 = 2 * n, b1 = 2 * n + 1;
    // Tread (normal radially out), counter-clockwise seen from outside.
    mesh.triangles.emplace_back(a0, b0, b1);
    mesh.triangles.emplace_back(a0, b1, a1);
    // Caps: +z cap faces +z, -z cap faces -z.
    mesh.triangles.emplace_back(front, a1, b1);
    mesh.triangles.emplace_back(back, b0, a0);
  }
  return mesh;
}

WheelPlacement PlaceWheels(const Mesh& body, const WheelOptions& options) {
  options.Check();
  SAMP_CHECK(!body.Empty()) << "PlaceWheels: the body mesh is empty";
  const AlignedBox box = body.Bounds();
  const Eigen::Vector3d size = box.Size();
  const double length = size.x(), body_width = size.z();
  WheelPlacement placement;
  placement.radius = options.radius > 0.0
                         ? options.radius
                         : std::clamp(options.radius_per_length * length, options.min_radius,
                                      options.max_radius);
  placement.width =
      options.width > 0.0 ? options.width : options.width_per_radius * placement.radius;
  const double half_track = 0.5 * body_width - options.side_inset - 0.5 * placement.width;
  SAMP_CHECK(half_track > 0.5 * placement.width)
      << "PlaceWheels: the body is " << body_width << " m wide, too narrow for two tyres "
      << placement.width << " m wide with side_inset " << options.side_inset << " m";
  // The body's bottom (largest y) goes to y = -ground_clearance.
  placement.lift = box.max.y() + options.ground_clearance;
  const double x_mid = box.Center().x() + options.axle_centre_offset_per_length * length;
  const double half_base = 0.5 * options.wheelbase_per_length * length;
  const double z_mid = box.Center().z();
  const double y = -placement.radius;
  placement.centers = {Eigen::Vector3d(x_mid + half_base, y, z_mid + half_track),
                       Eigen::Vector3d(x_mid + half_base, y, z_mid - half_track),
                       Eigen::Vector3d(x_mid - half_base, y, z_mid + half_track),
                       Eigen::Vector3d(x_mid - half_base, y, z_mid - half_track)};
  return placement;
}

WheeledCar AddWheels(const Mesh& body, const WheelOptions& options) {
  WheeledCar car;
  car.placement = PlaceWheels(body, options);
  car.body = body;
  const float lift = float(car.placement.lift);
  for (Eigen::Vector3f& v : car.body.vertices) v.y() -= lift;
  for (const Eigen::Vector3d& c : car.placement.centers) {
    car.wheels.Append(MakeWheelMesh(c, car.placement.radius, car.placement.width, options.segments));
  }
  return car;
}

}  // namespace samp
