#include "libsamp/data/observations.h"

#include <gtest/gtest.h>

#include <cmath>

#include "libsamp/core/error.h"
#include "libsamp/data/stereo.h"
#include "tests/testing/expect_error.h"

namespace samp {
namespace {

constexpr double kCarZ = 10.0;        // front face of the box car, m
constexpr double kRoadY = 1.65;       // road 1.65 m below the camera
constexpr double kCarTopY = 0.15;     // car roof at y = 0.15 (1.5 m high)
constexpr double kWallZ = 30.0;       // background wall

StereoCalibration Calibration() {
  StereoCalibration c;
  c.baseline = 0.54;
  return c;
}

// Disparity of a scene: the front face of a car (|x| <= 1, kCarTopY <= y <=
// kRoadY, z = kCarZ), the road y = kRoadY, a wall at kWallZ.
cv::Mat SceneDisparity(const StereoCalibration& c) {
  cv::Mat disparity(c.camera.height, c.camera.width, CV_32FC1);
  const double fb = c.camera.fx * c.baseline;
  for (int v = 0; v < disparity.rows; ++v)
    for (int u = 0; u < disparity.cols; ++u) {
      const Eigen::Vector3d ray = c.camera.Ray(u, v);
      double z = kWallZ;
      const Eigen::Vector3d on_face = ray * kCarZ;
      if (std::abs(on_face.x()) <= 1.0 && on_face.y() >= kCarTopY && on_face.y() <= kRoadY) {
        z = kCarZ;
      } else if (ray.y() > 0 && kRoadY / ray.y() < kWallZ) {
        z = kRoadY / ray.y();
      }
      disparity.at<float>(v, u) = static_cast<float>(fb / z);
    }
  return disparity;
}

TrackFrame CarFrame(const StereoCalibration& c, const Eigen::Isometry3d& world_from_camera) {
  TrackFrame frame;
  frame.frame = 4;
  frame.world_from_camera = world_from_camera;
  frame.ground_plane_in_world = TransformPlane(Eigen::Vector4d(0, -1, 0, kRoadY), world_from_camera);
  ObjectLabel& d = frame.detection;
  d.height = 1.5;
  d.width = 2.0;
  d.length = 2.0;
  d.position = Eigen::Vector3d(0, kRoadY, kCarZ + 1.0);  // bottom centre of a 2 m deep box
  const Eigen::Vector2d top_left = c.camera.Project(Eigen::Vector3d(-1, kCarTopY, kCarZ));
  const Eigen::Vector2d bottom_right = c.camera.Project(Eigen::Vector3d(1, kRoadY, kCarZ));
  d.box_2d << top_left.x(), top_left.y(), bottom_right.x(), bottom_right.y();
  return frame;
}

Eigen::Isometry3d SomePose() {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(5, -0.2, 40);
  return pose;
}

TEST(ObservationsTest, TransformPlaneAndCenter) {
  const Eigen::Isometry3d pose = SomePose();
  const Eigen::Vector4d plane_in_camera(0.01, -0.999, 0.02, 1.6);
  const Eigen::Vector4d plane_in_world = TransformPlane(plane_in_camera, pose);
  const Eigen::Vector3d x(2, 0.3, 9);
  EXPECT_NEAR(plane_in_world.head<3>().dot(pose * x) + plane_in_world[3],
              plane_in_camera.head<3>().dot(x) + plane_in_camera[3], 1e-12);
  ObjectLabel d;
  d.position = Eigen::Vector3d(1, 1.6, 12);
  d.height = 1.4;
  EXPECT_TRUE(DetectionCenter(d).isApprox(Eigen::Vector3d(1, 0.9, 12)));
}

TEST(ObservationsTest, PointsOfABoxCar) {
  const StereoCalibration c = Calibration();
  const cv::Mat disparity = SceneDisparity(c);
  const Eigen::Isometry3d pose = SomePose();
  TrackFrame frame = CarFrame(c, pose);
  ObservationOptions options;
  options.max_points_per_frame = 0;  // all
  const int total = ExtractObservations(disparity, c, options, 0, &frame);

  // Expected: the face pixels more than min_height_above_road above the road.
  int expected = 0;
  for (int v = 0; v < c.camera.height; ++v)
    for (int u = 0; u < c.camera.width; ++u) {
      const Eigen::Vector3d on_face = c.camera.Ray(u, v) * kCarZ;
      if (std::abs(on_face.x()) <= 1.0 && on_face.y() >= kCarTopY &&
          on_face.y() < kRoadY - options.min_height_above_road)
        ++expected;
    }
  ASSERT_GT(expected, 10000);
  EXPECT_NEAR(total, expected, 0.01 * expected);
  ASSERT_EQ(static_cast<int>(frame.candidate_points_in_world.size()), total);
  ASSERT_EQ(frame.candidate_sigmas.size(), frame.candidate_points_in_world.size());
  ASSERT_EQ(frame.candidate_disparities_px.size(), frame.candidate_points_in_world.size());
  ASSERT_EQ(frame.candidate_pixels.size(), frame.candidate_points_in_world.size());
  const double sigma = kCarZ * kCarZ * 1.0 / (c.baseline * c.camera.fx);  // 0.2567 m
  for (size_t i = 0; i < frame.candidate_points_in_world.size(); ++i) {
    const Eigen::Vector3d in_camera = pose.inverse() * frame.candidate_points_in_world[i];
    ASSERT_NEAR(in_camera.z(), kCarZ, 1e-3);  // no road, no wall
    // The pixel and disparity the point was made from.
    ASSERT_NEAR(c.baseline * c.camera.fx / frame.candidate_disparities_px[i], kCarZ, 1e-3);
    ASSERT_NEAR(c.camera.fx * in_camera.x() / in_camera.z() + c.camera.cx, frame.candidate_pixels[i].x(), 1e-3);
    ASSERT_NEAR(c.camera.fy * in_camera.y() / in_camera.z() + c.camera.cy, frame.candidate_pixels[i].y(), 1e-3);
    ASSERT_NEAR(frame.candidate_sigmas[i], sigma, 1e-4);
    ASSERT_GT(kRoadY - in_camera.y(), options.min_height_above_road - 1e-9);
  }
  EXPECT_NEAR(sigma, 0.25666, 1e-4);
  // sigma_disparity scales sigma_d.
  options.sigma_disparity_px = 0.5;
  ExtractObservations(disparity, c, options, 0, &frame);
  EXPECT_NEAR(frame.candidate_sigmas.front(), 0.5 * sigma, 1e-4);
}

TEST(ObservationsTest, DistanceGateAndRoadFilter) {
  const StereoCalibration c = Calibration();
  const cv::Mat disparity = SceneDisparity(c);
  TrackFrame frame = CarFrame(c, Eigen::Isometry3d::Identity());
  ObservationOptions options;
  options.max_points_per_frame = 0;
  options.max_distance_to_detection = 1.2;
  options.depth_gate_sigmas = 0.0;  // the sphere alone
  const int gated = ExtractObservations(disparity, c, options, 0, &frame);
  EXPECT_GT(gated, 0);
  const Eigen::Vector3d center = DetectionCenter(frame.detection);
  for (const Eigen::Vector3d& p : frame.candidate_points_in_world) ASSERT_LE((p - center).norm(), 1.2 + 1e-9);
  // The depth gate adds points whose ray passes within 1.2 m of the centre and
  // that lie within 1.2 m + 3 sigma_ray of it along the ray.
  options.depth_gate_sigmas = 3.0;
  const int depth_gated = ExtractObservations(disparity, c, options, 0, &frame);
  EXPECT_GE(depth_gated, gated);
  for (const Eigen::Vector3d& p : frame.candidate_points_in_world) {
    const Eigen::Vector3d u = p.normalized();
    const double along = center.dot(u);
    ASSERT_LE((center - along * u).norm(), 1.2 + 1e-9);
    const double sigma_ray = p.z() * p.z() / (c.baseline * c.camera.fx) / u.z();
    ASSERT_LE(std::abs(p.norm() - along), 1.2 + 3.0 * sigma_ray + 1e-9);
  }
  options.depth_gate_sigmas = 0.0;
  options.max_distance_to_detection = 4.0;
  const int all = ExtractObservations(disparity, c, options, 0, &frame);
  EXPECT_GT(all, gated);
  // A higher road threshold removes the lower part of the car.
  options.min_height_above_road = 0.8;
  const int high = ExtractObservations(disparity, c, options, 0, &frame);
  EXPECT_LT(high, all);
  for (const Eigen::Vector3d& p : frame.candidate_points_in_world) ASSERT_LT(p.y(), kRoadY - 0.8 + 1e-9);
  // The margin lets in more of the road and wall, but they are filtered out.
  options.min_height_above_road = 0.15;
  options.box_margin = 0.5;
  EXPECT_EQ(ExtractObservations(disparity, c, options, 0, &frame), all);
  // A box outside the image yields no points, no error.
  frame.detection.box_2d << -500, -400, -100, -50;
  EXPECT_EQ(ExtractObservations(disparity, c, options, 0, &frame), 0);
  EXPECT_TRUE(frame.candidate_points_in_world.empty());
}

TEST(ObservationsTest, SignedDistanceToBox) {
  ObjectLabel d;
  d.height = 1.5;
  d.width = 2.0;
  d.length = 4.0;
  d.position = Eigen::Vector3d(1, 1.6, 20);  // centre (1, 0.85, 20)
  d.rotation_y = 0.0;                        // length along the camera's x
  EXPECT_NEAR(SignedDistanceToBox(d, Eigen::Vector3d(1, 0.85, 20)), -0.75, 1e-12);  // half the height
  EXPECT_NEAR(SignedDistanceToBox(d, Eigen::Vector3d(3.5, 0.85, 20)), 0.5, 1e-12);  // beyond the front
  EXPECT_NEAR(SignedDistanceToBox(d, Eigen::Vector3d(1, 0.85, 21.5)), 0.5, 1e-12);  // beside it
  EXPECT_NEAR(SignedDistanceToBox(d, Eigen::Vector3d(4, 0.85, 22)), std::sqrt(1.0 + 1.0), 1e-12);  // corner
  // Turned by 90 degrees the length runs along the camera's z.
  d.rotation_y = M_PI / 2;
  EXPECT_NEAR(SignedDistanceToBox(d, Eigen::Vector3d(1, 0.85, 22.5)), 0.5, 1e-9);
  EXPECT_NEAR(SignedDistanceToBox(d, Eigen::Vector3d(2.5, 0.85, 20)), 0.5, 1e-9);
}

TEST(ObservationsTest, NearerBoxesClaimTheirPoints) {
  const StereoCalibration c = Calibration();
  const cv::Mat disparity = SceneDisparity(c);
  ObservationOptions options;
  options.max_points_per_frame = 0;
  TrackFrame frame = CarFrame(c, Eigen::Isometry3d::Identity());
  const int alone = ExtractObservations(disparity, c, options, 0, &frame);
  ASSERT_GT(alone, 1000);
  // A hidden car's detection 3 m behind the face: the box car in front (the
  // face is its rear) claims the face, so the hidden car keeps none of it ...
  TrackFrame hidden = frame;
  hidden.detection.position.z() += 3.0;
  const ObjectLabel front = frame.detection;
  EXPECT_GT(ExtractObservations(disparity, c, options, 1, &hidden), 0);
  EXPECT_EQ(ExtractObservations(disparity, c, options, 1, &hidden, {front}), 0);
  // ... while the car in front keeps all of it, and so does a car without
  // rivals or with the claims off (the paper).
  EXPECT_EQ(ExtractObservations(disparity, c, options, 0, &frame, {hidden.detection}), alone);
  options.nearest_box_claims = false;
  EXPECT_GT(ExtractObservations(disparity, c, options, 1, &hidden, {front}), 0);
  // A neighbour's (noisy) box overlapping the car's right quarter, the face
  // 0.3 m deep inside it, claims that quarter: the points nearer its box.
  options.nearest_box_claims = true;
  ObjectLabel right = frame.detection;
  right.position.x() += 1.5;
  right.position.z() -= 0.3;
  const int shared = ExtractObservations(disparity, c, options, 0, &frame, {right});
  EXPECT_LT(shared, alone);
  EXPECT_GT(shared, alone / 2);
  for (const Eigen::Vector3d& p : frame.candidate_points_in_world)
    ASSERT_LE(SignedDistanceToBox(frame.detection, p), SignedDistanceToBox(right, p));
}

TEST(ObservationsTest, SubsamplingIsBoundedAndSeeded) {
  const StereoCalibration c = Calibration();
  const cv::Mat disparity = SceneDisparity(c);
  ObservationOptions options;
  options.max_points_per_frame = 500;
  TrackFrame a = CarFrame(c, Eigen::Isometry3d::Identity());
  TrackFrame b = a, other_track = a;
  const int total = ExtractObservations(disparity, c, options, 3, &a);
  EXPECT_GT(total, 500);
  ASSERT_EQ(a.candidate_points_in_world.size(), 500u);
  ExtractObservations(disparity, c, options, 3, &b);
  ExtractObservations(disparity, c, options, 4, &other_track);
  EXPECT_EQ(a.candidate_points_in_world, b.candidate_points_in_world);
  EXPECT_NE(a.candidate_points_in_world, other_track.candidate_points_in_world);
  // Spread over the whole face, not a clump: the subsample spans most of it.
  double min_x = 1e9, max_x = -1e9;
  for (const Eigen::Vector3d& p : a.candidate_points_in_world) {
    min_x = std::min(min_x, p.x());
    max_x = std::max(max_x, p.x());
  }
  EXPECT_GT(max_x - min_x, 1.8);
}

TEST(ObservationsTest, OptionsCheck) {
  ObservationOptions options;
  EXPECT_NO_THROW(options.Check());
  options.sigma_disparity_px = 0;
  test::ExpectError([&] { options.Check(); }, {"ObservationOptions.sigma_disparity_px"});
  options = ObservationOptions();
  options.max_points_per_frame = -1;
  test::ExpectError([&] { options.Check(); }, {"ObservationOptions.max_points_per_frame"});
}

}  // namespace
}  // namespace samp

namespace samp {
namespace {

// The one detection gate (InDetectionGate) of the candidates and the fitter:
// a sphere, or the ray gate around it, the same in any frame.
TEST(DetectionGate, SphereOrAlongTheRayWithinTheNoiseAtTheCentresDepth) {
  DetectionGate gate;
  gate.box_centre = Eigen::Vector3d(0.0, 0.9, 20.0);
  gate.radius = 4.0;
  const Eigen::Vector3d& c = gate.box_centre;
  const Eigen::Vector3d behind = c * (25.0 / 20.0);  // 5 m behind on the centre's ray
  EXPECT_TRUE(InDetectionGate(gate, c + Eigen::Vector3d(3.9, 0.0, 0.0)));
  EXPECT_FALSE(InDetectionGate(gate, c + Eigen::Vector3d(4.1, 0.0, 0.0)));
  EXPECT_FALSE(InDetectionGate(gate, behind));  // ray_sigmas 0: the sphere alone
  gate.ray_sigmas = 3.0;
  gate.depth_sigma_at_centre = 0.5;  // 4 m + 1.5 m along the ray
  EXPECT_TRUE(InDetectionGate(gate, behind));
  EXPECT_TRUE(InDetectionGate(gate, c * (15.0 / 20.0)));   // 5 m in front
  EXPECT_FALSE(InDetectionGate(gate, c * (26.0 / 20.0)));  // 6 m behind
  // Its ray passes the centre by more than the radius (4.4 m): out, although
  // its depth is within the along-ray gate.
  EXPECT_FALSE(InDetectionGate(gate, c + Eigen::Vector3d(4.5, 0.0, 0.0)));
  gate.depth_sigma_at_centre = 0.2;  // 4 m + 0.6 m
  EXPECT_FALSE(InDetectionGate(gate, behind));

  // The same decisions in another frame (world: camera moved and turned).
  gate.depth_sigma_at_centre = 0.5;
  const Eigen::Isometry3d world_from_camera =
      Eigen::Translation3d(5.0, -1.0, 30.0) * Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitY());
  DetectionGate world = gate;
  world.camera_centre = world_from_camera.translation();
  world.optical_axis = world_from_camera.linear().col(2);
  world.box_centre = world_from_camera * gate.box_centre;
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(c + Eigen::Vector3d(3.9, 0.0, 0.0)), behind,
                                   Eigen::Vector3d(c * (26.0 / 20.0)),
                                   Eigen::Vector3d(c + Eigen::Vector3d(4.5, 0.0, 0.0))}) {
    EXPECT_EQ(InDetectionGate(world, world_from_camera * p), InDetectionGate(gate, p)) << p.transpose();
  }
}

}  // namespace
}  // namespace samp
