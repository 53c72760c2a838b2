#include "libsamp/data/road_plane.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "libsamp/core/error.h"
#include "tests/testing/expect_error.h"

namespace samp {
namespace {

// Points on the plane n . x + d = 0 (camera frame) in front of the camera,
// with Gaussian noise, plus uniformly scattered outliers.
std::vector<StereoPoint> RoadScene(const Eigen::Vector4d& plane, int inliers, int outliers,
                                   double noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-10, 10), z(4, 35), any_y(-3, 2.5);
  std::normal_distribution<double> gauss(0, noise);
  std::vector<StereoPoint> points;
  const Eigen::Vector3d n = plane.head<3>();
  for (int i = 0; i < inliers; ++i) {
    StereoPoint p;
    const double px = x(rng), pz = z(rng);
    const double py = -(n.x() * px + n.z() * pz + plane[3]) / n.y();  // on the plane
    p.point_in_camera = Eigen::Vector3d(px, py, pz) + n * gauss(rng);
    points.push_back(p);
  }
  for (int i = 0; i < outliers; ++i) {  // walls, cars, noise: anywhere
    StereoPoint p;
    p.point_in_camera = Eigen::Vector3d(x(rng), any_y(rng), z(rng));
    points.push_back(p);
  }
  return points;
}

TEST(RoadPlaneTest, RecoversAKnownPlaneWithOutliers) {
  Eigen::Vector3d normal(0.03, -1.0, -0.02);
  normal.normalize();
  const Eigen::Vector4d truth(normal.x(), normal.y(), normal.z(), 1.62);
  const std::vector<StereoPoint> points = RoadScene(truth, 6000, 4000, 0.02, 3);
  RoadPlaneOptions options;
  RoadPlaneSummary summary;
  const Eigen::Vector4d plane = EstimateRoadPlane(points, options, &summary);
  ASSERT_TRUE(summary.success) << summary.BriefReport();
  EXPECT_NEAR(plane.head<3>().norm(), 1.0, 1e-9);
  EXPECT_LT(plane.y(), 0);
  const double angle_deg = std::acos(std::min(1.0, plane.head<3>().dot(normal))) * 180 / M_PI;
  EXPECT_LT(angle_deg, 0.2);
  EXPECT_NEAR(plane[3], 1.62, 0.01);
  EXPECT_GT(summary.num_inliers, 5000);
  EXPECT_LT(summary.rms_inlier_distance, 0.03);
  // Deterministic for a seed.
  RoadPlaneSummary again;
  EXPECT_EQ(EstimateRoadPlane(points, options, &again), plane);
  EXPECT_EQ(again.num_inliers, summary.num_inliers);
}

TEST(RoadPlaneTest, SubsamplesLargeInputs) {
  const Eigen::Vector4d truth(0, -1, 0, 1.7);
  const std::vector<StereoPoint> points = RoadScene(truth, 30000, 10000, 0.01, 5);
  RoadPlaneOptions options;
  options.max_points = 5000;
  RoadPlaneSummary summary;
  const Eigen::Vector4d plane = EstimateRoadPlane(points, options, &summary);
  ASSERT_TRUE(summary.success);
  EXPECT_LE(summary.num_points, 5000);
  EXPECT_NEAR(plane[3], 1.7, 0.01);
}

TEST(RoadPlaneTest, ReportsFailureAndReturnsTheDefault) {
  RoadPlaneOptions options;
  RoadPlaneSummary summary;
  // Too few points.
  Eigen::Vector4d plane = EstimateRoadPlane(RoadScene(Eigen::Vector4d(0, -1, 0, 1.6), 50, 0, 0.01, 1), options, &summary);
  EXPECT_FALSE(summary.success);
  EXPECT_FALSE(summary.message.empty());
  EXPECT_EQ(plane, Eigen::Vector4d(0, -1, 0, 1.65));
  // A steep plane (a wall-like slope, 40 degrees) is not a road.
  Eigen::Vector3d steep(0, -1, std::tan(40 * M_PI / 180));
  steep.normalize();
  plane = EstimateRoadPlane(RoadScene(Eigen::Vector4d(steep.x(), steep.y(), steep.z(), 1.6), 3000, 0, 0.01, 2),
                            options, &summary);
  EXPECT_FALSE(summary.success) << summary.BriefReport();
  EXPECT_NE(summary.BriefReport().find("failed"), std::string::npos);
}

TEST(RoadPlaneTest, OptionsCheck) {
  RoadPlaneOptions options;
  EXPECT_NO_THROW(options.Check());
  options.inlier_threshold = 0;
  test::ExpectError([&] { options.Check(); }, {"RoadPlaneOptions.inlier_threshold"});
  options = RoadPlaneOptions();
  options.min_camera_height = 4;
  test::ExpectError([&] { options.Check(); }, {"RoadPlaneOptions.min_camera_height"});
}

}  // namespace
}  // namespace samp
