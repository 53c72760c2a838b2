// Association of a frame's candidate points (association.h): the detection
// gate per data term, the even solve subsample and the effective count.
#include "libsamp/fit/association.h"

#include <gtest/gtest.h>

#include <vector>

#include "libsamp/fit/costs/disparity.h"

namespace samp {
namespace {

// A detection 20 m ahead (box centre (0, 0.9, 20): bottom 1.65 m below the
// camera, 1.5 m high), camera at the world origin looking along +z.
TrackFrame FrameAhead() {
  TrackFrame f;
  f.detection.position = Eigen::Vector3d(0.0, 1.65, 20.0);
  f.detection.height = 1.5;
  return f;
}

TEST(Association, DetectionGateIsASphereForThePointTermsAndFollowsTheRayForDisparity) {
  TrackFrame f = FrameAhead();
  const Eigen::Vector3d centre(0.0, 0.9, 20.0);
  f.candidate_points_in_world = {centre + Eigen::Vector3d(2.9, 0.0, 0.0),   // inside the sphere
                                 centre * (23.5 / 20.0),                    // 3.5 m behind, on the centre's ray
                                 centre + Eigen::Vector3d(3.5, 0.0, 0.0)};  // 3.5 m beside
  f.candidate_sigmas = {0.5, 0.5, 0.5};
  const Association sphere = AssociateByDetection(f, 3.0, DataTerm::kRayDepth);
  ASSERT_EQ(sphere.points.size(), 1u);
  EXPECT_EQ(sphere.points[0], f.candidate_points_in_world[0]);
  EXPECT_EQ(AssociateByDetection(f, 3.0, DataTerm::kPaper).points.size(), 1u);
  // Disparity: along the ray within 3 m + 3 sigma (0.5 m scaled to the
  // centre's depth, ~0.36 m), so the point 3.5 m behind is kept.
  const Association ray = AssociateByDetection(f, 3.0, DataTerm::kDisparity);
  ASSERT_EQ(ray.points.size(), 2u);
  EXPECT_EQ(ray.points[1], f.candidate_points_in_world[1]);
  EXPECT_EQ(ray.sigmas[1], 0.5);
  // With a small sigma the same point falls outside the ray gate too.
  f.candidate_sigmas = {0.05, 0.05, 0.05};
  EXPECT_EQ(AssociateByDetection(f, 3.0, DataTerm::kDisparity).points.size(), 1u);
}

TEST(Association, DisparityDropsAndCountsPointsBehindTheCamera) {
  // A point behind the camera has no disparity; with a large sigma it would
  // pass the ray gate (its sigma scaled to the centre's depth is huge).
  TrackFrame f = FrameAhead();
  const Eigen::Vector3d centre(0.0, 0.9, 20.0);
  f.candidate_points_in_world = {centre, -0.5 * centre, Eigen::Vector3d(3.0, 0.0, 0.0), centre * 1.01};
  f.candidate_sigmas = {0.5, 5.0, 5.0, 0.5};
  const Association ray = AssociateByDetection(f, 3.0, DataTerm::kDisparity);
  EXPECT_EQ(ray.behind_camera, 2);  // behind it, and beside it at depth 0
  ASSERT_EQ(ray.points.size(), 2u);
  EXPECT_EQ(ray.points[0], f.candidate_points_in_world[0]);
  EXPECT_EQ(ray.points[1], f.candidate_points_in_world[3]);
  EXPECT_EQ(AssociateByDetection(f, 3.0, DataTerm::kRayDepth).behind_camera, 0);  // counted for disparity only
  EXPECT_TRUE(InFrontOfCamera(centre, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()));
  EXPECT_FALSE(InFrontOfCamera(-centre, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()));
  EXPECT_FALSE(InFrontOfCamera(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()));
}

TEST(Association, SolveSubsampleSpreadsEvenlyAndKeepsSmallAssociations) {
  Association a;
  for (int i = 0; i < 10; ++i) {
    a.points.push_back(Eigen::Vector3d(i, 0.0, 0.0));
    a.sigmas.push_back(0.1 * (i + 1));
  }
  const Association all = SolveSubsample(a, 0);
  EXPECT_EQ(all.points.size(), 10u);
  EXPECT_EQ(SolveSubsample(a, 10).points.size(), 10u);
  const Association four = SolveSubsample(a, 4);  // k = floor((j + 1/2) 10 / 4) = 1, 3, 6, 8
  ASSERT_EQ(four.points.size(), 4u);
  const int expected[4] = {1, 3, 6, 8};
  for (int j = 0; j < 4; ++j) {
    EXPECT_EQ(four.points[j].x(), expected[j]);
    EXPECT_DOUBLE_EQ(four.sigmas[j], 0.1 * (expected[j] + 1));
  }
}

TEST(Association, EffectivePointsCountsCorrelationAreas) {
  TrackFrame f;
  f.candidate_pixels_per_point = 4.0;
  FitOptions options;
  options.correlation_area_px = 80.0;
  EXPECT_DOUBLE_EQ(EffectivePoints(f, 1000, options), 50.0);
  f.candidate_pixels_per_point = 200.0;
  EXPECT_DOUBLE_EQ(EffectivePoints(f, 1000, options), 1000.0);  // at most n
  options.data_weighting = DataWeighting::kMean;
  EXPECT_DOUBLE_EQ(EffectivePoints(f, 1000, options), 1000.0);
}

}  // namespace
}  // namespace samp
