// Stereo points that may belong to a detected car: the candidate observations
// of one track frame (TrackFrame::candidate_*).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "libsamp/data/track.h"

namespace samp {

struct ObservationOptions {
  // The detection's 2D box is enlarged by this fraction of its width/height on each side.
  double box_margin = 0.1;
  // Points must be higher than this above the road plane, m.
  double min_height_above_road = 0.15;
  // Points must be within this distance of the detected 3D box centre
  // (bottom centre lifted by h/2), m. Larger than the paper's 3 m on purpose:
  // the fitter gates to 3 m around the detection, and re-associates around
  // its fitted trajectory (hard EM) from this larger set.
  double max_distance_to_detection = 4.0;
  // ... or, when its viewing ray passes within max_distance_to_detection of
  // the centre, within max_distance_to_detection + depth_gate_sigmas
  // sigma_ray of it along the ray (sigma_ray = sigma_d at the centre's depth
  // / cos of the ray to the optical axis): far away the stereo noise along the ray (metres)
  // exceeds the sphere, which would cut it unevenly about a detection that is
  // itself off along the ray. 0 = the sphere alone.
  double depth_gate_sigmas = 3.0;
  // Disparities below this are ignored (too far / unreliable), px.
  double min_disparity_px = 1.0;
  // Disparity noise used for sigma_d = z^2 sigma_disparity / (b f), px.
  double sigma_disparity_px = 1.0;
  // At most this many candidates per frame (uniform subsample, seeded); 0 = all.
  int max_points_per_frame = 5000;
  // Seed of the subsampling; combined with the track id and frame number.
  std::uint64_t seed = 0;
  // Occlusion and parked rows: a point that lies nearer to another detection
  // of the same frame (signed distance to its 3D box, SignedDistanceToBox) than
  // to this one is that car's, not this one's. Without it, the car in front
  // of a partly hidden one lends it its rear and side, and the hidden car's
  // fit moves towards the camera by up to the gap between the two
  // (docs/fitting.md, "Association"). false = every track sees every point
  // in its 2D box (the paper).
  bool nearest_box_claims = true;

  void Check() const;  // throws samp::Error naming the field
};

// Fills frame->candidate_points_in_world, candidate_sigmas, candidate_pixels
// and candidate_disparities_px
// from the pixels of `disparity_px` (CV_32FC1, 0 = invalid) inside the
// enlarged 2D box of frame->detection, keeping points above the road
// (frame->ground_plane_in_world) and near the detection, mapped to world by
// frame->world_from_camera. Points are ordered by pixel (row-major) after
// subsampling. Returns the number of points before subsampling. Does not
// throw on an empty result (a frame may legitimately have no points).
// `rivals` are the other detections of the same frame (same camera); with
// options.nearest_box_claims a point nearer to one of their boxes than to
// this detection's box is left out.
int ExtractObservations(const cv::Mat& disparity_px, const StereoCalibration& calibration,
                        const ObservationOptions& options, int track_id, TrackFrame* frame,
                        const std::vector<ObjectLabel>& rivals = {});

// Signed distance of a point (camera frame of the detection) to the
// detection's 3D box (KITTI convention: bottom centre `position`, yaw
// rotation_y about the camera's y axis, length along the car): negative
// inside (minus the distance to the nearest face), m.
double SignedDistanceToBox(const ObjectLabel& detection, const Eigen::Vector3d& point_in_camera);

// The detection gate of a stereo point, shared by the candidates
// (ExtractObservations) and the fitter's first association: the point lies
// within `radius` of the detected box's centre (a sphere), or, with
// ray_sigmas > 0, its viewing ray from the camera passes within `radius` of
// the centre and its distance along the ray lies within radius + ray_sigmas
// sigma_ray of the centre's, sigma_ray = depth_sigma_at_centre / cos(ray,
// optical axis). Far away the stereo noise along the ray (metres) exceeds the
// sphere, which would cut it unevenly about a detection that is itself off
// along the ray. Any frame (camera, world), as long as all four agree.
struct DetectionGate {
  Eigen::Vector3d camera_centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d optical_axis = Eigen::Vector3d::UnitZ();  // unit
  Eigen::Vector3d box_centre = Eigen::Vector3d::Zero();     // DetectionCenter
  double radius = 3.0;                 // m
  double ray_sigmas = 0.0;             // 0 = the sphere alone
  double depth_sigma_at_centre = 0.0;  // sigma_d at the box centre's depth, m
};
bool InDetectionGate(const DetectionGate& gate, const Eigen::Vector3d& point);

// Plane transforms: a plane (n, d) in frame A (n . x_A + d = 0) to frame B
// given b_from_a. Keeps n unit and pointing the same way.
Eigen::Vector4d TransformPlane(const Eigen::Vector4d& plane_in_a, const Eigen::Isometry3d& b_from_a);

// Centre of the detection's 3D box in its camera: position - (0, h/2, 0).
Eigen::Vector3d DetectionCenter(const ObjectLabel& detection);

}  // namespace samp
