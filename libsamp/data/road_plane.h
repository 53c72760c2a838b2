// Road plane from stereo points by RANSAC, for frames without a planes/ file.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "libsamp/data/stereo.h"

namespace samp {

struct RoadPlaneOptions {
  // RANSAC hypotheses (3-point samples).
  int iterations = 300;
  // Point-to-plane distance below which a point is an inlier, m.
  double inlier_threshold = 0.08;
  // Only points below the camera (y > min_point_height_below_camera) and
  // nearer than max_depth are used: the road is below and in front.
  double min_point_height_below_camera = 0.5;
  double max_depth = 40.0;
  // Hypotheses whose normal is further than this from the camera's -y axis are rejected, degrees.
  double max_tilt_deg = 15.0;
  // Accepted camera heights above the plane, m.
  double min_camera_height = 0.8;
  double max_camera_height = 3.0;
  // At most this many points are used (uniformly subsampled, seeded).
  int max_points = 20000;
  // The fit fails when fewer inliers than this remain.
  int min_inliers = 200;
  std::uint64_t seed = 0;

  void Check() const;  // throws samp::Error naming the field
};

struct RoadPlaneSummary {
  bool success = false;
  int num_points = 0;   // points considered after filtering/subsampling
  int num_inliers = 0;  // of the final least-squares plane
  double rms_inlier_distance = 0.0;  // m
  std::string message;  // why it failed, empty on success
  std::string BriefReport() const;
};

// Fits n . x + d = 0 (n unit, pointing up, i.e. n.y() < 0; d = camera height)
// to points in the camera frame: RANSAC on 3-point samples under the
// options' tilt and height limits, then least squares on the inliers. On
// failure (too few points or inliers) returns the KITTI default
// (0, -1, 0, 1.65) with summary->success = false; never throws on data.
Eigen::Vector4d EstimateRoadPlane(const std::vector<StereoPoint>& points,
                                  const RoadPlaneOptions& options, RoadPlaneSummary* summary);

}  // namespace samp
