// Data passed from the sequence readers / tracker to the fitter. Frames:
// camera_t = left camera of frame t (KITTI: x right, y down, z forward);
// world = the frame of the ego poses (poses/<seq>.txt maps camera_t -> world).
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "libsamp/core/camera.h"

namespace samp {

struct StereoCalibration {
  PinholeCamera camera;   // left (P2) intrinsics and image size
  double baseline = 0.0;  // metres, from P2 and P3
};

// One KITTI label line (detection, ground truth or result), camera frame of its frame.
struct ObjectLabel {
  int frame = -1;       // -1 when the file has no frame column
  int track_id = -1;    // -1 when unknown
  std::string type = "Car";
  double truncation = 0.0;
  int occlusion = 0;
  double alpha = 0.0;
  Eigen::Vector4d box_2d = Eigen::Vector4d::Zero();  // x1 y1 x2 y2, px
  double height = 0.0, width = 0.0, length = 0.0;    // h w l, metres
  Eigen::Vector3d position = Eigen::Vector3d::Zero(); // bottom centre in the camera, metres
  double rotation_y = 0.0;                            // ry, radians
  double score = 1.0;
};

// Everything the fitter needs of one frame of one track.
struct TrackFrame {
  int frame = 0;                     // frame number within the sequence
  double time = 0.0;                 // seconds (frame / 10 Hz for KITTI)
  ObjectLabel detection;             // camera frame of this frame
  // Covariance of detection.position (camera frame, m^2) under the detector
  // noise model (DetectionCovariance in tracking.h); zero = unknown, and the
  // fitter then does not use the detection as a pose observation.
  Eigen::Matrix3d detection_covariance = Eigen::Matrix3d::Zero();
  Eigen::Isometry3d world_from_camera = Eigen::Isometry3d::Identity();
  // Road plane in world coordinates: n . x + d = 0, n unit, pointing up (towards -y of the camera).
  Eigen::Vector4d ground_plane_in_world = Eigen::Vector4d(0, -1, 0, 1.65);
  // Stereo points in world coordinates that may belong to the car (inside the
  // enlarged 2D box, above the road), with their depth-dependent std. dev. sigma_d.
  std::vector<Eigen::Vector3d> candidate_points_in_world;
  std::vector<double> candidate_sigmas;
  // Where each candidate was seen: its pixel (u, v) in the left image and its
  // disparity, px (empty when the points were not made from a disparity map).
  std::vector<Eigen::Vector2f> candidate_pixels;
  std::vector<float> candidate_disparities_px;
  // Image pixels each candidate stands for (>= 1: the candidates may be a
  // subsample of the valid pixels); the fitter's effective observation count.
  double candidate_pixels_per_point = 1.0;
};

struct Track {
  int id = 0;
  std::string sequence;
  std::string type = "Car";
  StereoCalibration calibration;
  // Increasing frame numbers, one per frame with a detection: gaps are possible
  // where the detector missed the car (use TrackFrame::time for dt).
  std::vector<TrackFrame> frames;
};

}  // namespace samp
