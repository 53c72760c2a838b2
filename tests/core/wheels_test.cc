#include "libsamp/core/wheels.h"

#include <gtest/gtest.h>

#include <map>
#include <utility>

#include "libsamp/core/error.h"

namespace samp {
namespace {

// Every directed edge appears once and its reverse once: closed and consistently oriented.
bool IsClosedAndOriented(const Mesh& mesh) {
  std::map<std::pair<int, int>, int> edges;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    for (int e = 0; e < 3; ++e) ++edges[{t[e], t[(e + 1) % 3]}];
  }
  for (const auto& [edge, count] : edges) {
    if (count != 1) return false;
    const auto reverse = edges.find({edge.second, edge.first});
    if (reverse == edges.end() || reverse->second != 1) return false;
  }
  return true;
}

// Signed volume (positive for outward-facing closed meshes).
double Volume(const Mesh& mesh) {
  double volume = 0.0;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[size_t(t[0])].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[size_t(t[1])].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[size_t(t[2])].cast<double>();
    volume += a.dot(b.cross(c)) / 6.0;
  }
  return volume;
}

TEST(Wheels, TyreIsAClosedOutwardCylinder) {
  const Mesh tyre = MakeWheelMesh(Eigen::Vector3d(1, -0.3, 0.5), 0.3, 0.2, 64);
  EXPECT_TRUE(IsClosedAndOriented(tyre));
  // A 64-gon prism: (n/2) r^2 sin(2 pi / n) * width.
  const double expected = 32 * 0.09 * std::sin(2 * M_PI / 64) * 0.2;
  EXPECT_NEAR(Volume(tyre), expected, 1e-6);
  EXPECT_NEAR(tyre.Bounds().max.y(), 0.0, 1e-6);
}

TEST(Wheels, BodyIsLiftedAndTyresTouchTheRoad) {
  // A canonical body: 4.0 x 1.2 x 1.7 m box, bottom at y = 0.
  const Mesh body = MakeBoxMesh(Eigen::Vector3d(-2.0, -1.2, -0.85), Eigen::Vector3d(2.0, 0.0, 0.85));
  WheelOptions options;
  const WheeledCar car = AddWheels(body, options);
  const WheelPlacement& p = car.placement;
  EXPECT_NEAR(p.radius, 0.078 * 4.0, 1e-6);
  EXPECT_NEAR(p.width, 0.65 * p.radius, 1e-9);
  EXPECT_NEAR(p.lift, options.ground_clearance, 1e-6);
  EXPECT_NEAR(car.body.Bounds().max.y(), -options.ground_clearance, 1e-6);
  EXPECT_NEAR(car.body.Bounds().min.y(), -1.2 - options.ground_clearance, 1e-6);
  // The tyres touch y = 0 and nothing lies below.
  const AlignedBox wheels = car.wheels.Bounds();
  EXPECT_NEAR(wheels.max.y(), 0.0, 1e-6);
  EXPECT_NEAR(car.Combined().Bounds().max.y(), 0.0, 1e-6);
  // Wheelbase 60 % of the length, outer faces 2 cm inside the sides, inside the body's length.
  EXPECT_NEAR(p.centers[0].x() - p.centers[2].x(), 2.4, 1e-6);
  EXPECT_NEAR(p.centers[0].z() + 0.5 * p.width, 0.85 - options.side_inset, 1e-6);
  EXPECT_NEAR(p.centers[1].z() - 0.5 * p.width, -0.85 + options.side_inset, 1e-6);
  EXPECT_LT(wheels.max.x(), 2.0);
  EXPECT_GT(wheels.min.x(), -2.0);
  EXPECT_EQ(car.wheels.triangles.size(), size_t(4 * 4 * options.segments));
  EXPECT_TRUE(IsClosedAndOriented(car.wheels));
  EXPECT_EQ(car.Combined().triangles.size(), body.triangles.size() + car.wheels.triangles.size());
  EXPECT_NE(p.BriefReport().find("lifted by 0.14"), std::string::npos) << p.BriefReport();
}

TEST(Wheels, FixedRadiusAndOffsetAreHonoured) {
  // Body not at the canonical bottom: its bottom (y = 0.3) goes to -clearance all the same.
  const Mesh body = MakeBoxMesh(Eigen::Vector3d(-1.0, -1.0, -0.9), Eigen::Vector3d(3.0, 0.3, 0.9));
  WheelOptions options;
  options.radius = 0.35;
  options.width = 0.25;
  options.axle_centre_offset_per_length = 0.05;
  options.ground_clearance = 0.2;
  const WheeledCar car = AddWheels(body, options);
  EXPECT_NEAR(car.placement.lift, 0.5, 1e-6);
  EXPECT_NEAR(car.body.Bounds().max.y(), -0.2, 1e-6);
  EXPECT_NEAR(car.placement.centers[0].y(), -0.35, 1e-12);
  EXPECT_NEAR(0.5 * (car.placement.centers[0].x() + car.placement.centers[2].x()), 1.0 + 0.2, 1e-6);
}

TEST(Wheels, CheckNamesTheField) {
  WheelOptions options;
  options.wheelbase_per_length = 1.2;
  try {
    options.Check();
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("wheelbase_per_length"), std::string::npos) << e.what();
  }
  options = WheelOptions();
  options.segments = 4;
  EXPECT_THROW(options.Check(), Error);
  // Too narrow a body.
  const Mesh thin = MakeBoxMesh(Eigen::Vector3d(-2, -1, -0.2), Eigen::Vector3d(2, 0, 0.2));
  EXPECT_THROW(AddWheels(thin, WheelOptions()), Error);
  EXPECT_THROW(AddWheels(Mesh(), WheelOptions()), Error);
}

}  // namespace
}  // namespace samp
