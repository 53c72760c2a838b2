// A finished `samp fit` run as the pictures and the web viewer see it: per
// sequence the camera, the ego poses, the left images, and per track the
// fitted mesh, the fitted and the detected pose of every frame and the
// associated stereo points. Read back from the run's files (tracks.json,
// meshes/, the sequence directories named there) by LoadFitRun, through the
// formats' owners (pipeline/fit_output.h, pipeline/fit_config.h, data/).
// Plain data; safe to read from many threads.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "libsamp/core/camera.h"
#include "libsamp/core/mesh.h"

namespace samp {

// world_from_object of a car at `position` (the bottom centre) with yaw θ
// about the y axis: [R_y(θ) | t], R_y = [[c,0,s],[0,1,0],[-s,0,c]] (KITTI's
// rotation_y convention; docs/fitting.md, "Parameterisation").
Eigen::Isometry3d PoseFromYaw(const Eigen::Vector3d& position, double yaw);

// One frame of one fitted track (world = the frame of the ego poses).
struct TrackFrameView {
  int frame = 0;
  double time = 0.0;                       // seconds
  Eigen::Isometry3d world_from_object = Eigen::Isometry3d::Identity();  // fitted
  double speed = 0.0, yaw_rate = 0.0;      // m/s, rad/s (fitted)
  std::string motion_model;
  int num_points = 0;
  double data_cost = 0.0;
  // The detection of this frame (the fit's input), when one is known.
  bool has_detection = false;
  Eigen::Isometry3d world_from_detection = Eigen::Isometry3d::Identity();
  Eigen::Vector3d detection_size = Eigen::Vector3d::Zero();  // l h w (object x y z), m
  Eigen::Vector4d detection_box_2d = Eigen::Vector4d::Zero();  // x1 y1 x2 y2, px
  // The stereo points the fit associated with the car in this frame.
  std::vector<Eigen::Vector3f> points_in_world;
};

struct TrackView {
  int id = 0;
  std::string type = "Car";
  std::string mode = "joint";              // "joint" or "single_frame"
  Mesh mesh;                                // fitted surface, object frame (may be empty)
  Eigen::VectorXd shape_code;              // z
  Eigen::VectorXd code_in_sigmas;          // z_i / sigma_i when the model's sigmas are known, else empty
  AlignedBox box;                          // extent of the fitted shape, object frame
  double initial_cost = 0.0, final_cost = 0.0;
  int num_iterations = 0;
  double seconds = 0.0;
  std::vector<TrackFrameView> frames;      // increasing frame numbers
  // Filled from ground truth (SEQ/gt) when the sequence has it; see GroundTruthView.
  int gt_track_id = -1;
  // Per mesh vertex: distance (m) to the ground-truth surface of the matched
  // car, placed at the poses of `error_frame`; empty without ground truth.
  std::vector<float> vertex_errors;
  int error_frame = -1;
};

// A ground-truth car of a synthetic sequence (SEQ/gt/label_02 and gt/meshes).
struct GroundTruthCarView {
  int id = 0;
  Mesh mesh;                               // object frame
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  // l h w, m
  std::map<int, Eigen::Isometry3d> world_from_object;  // per frame
};

struct SequenceView {
  std::string name, directory;
  PinholeCamera camera;                    // left camera (calib P2 + image size)
  std::vector<int> frames;                 // every frame of the sequence
  std::map<int, Eigen::Isometry3d> world_from_camera;  // per frame (identity without poses/)
  std::map<int, std::string> left_images;  // per frame, existing files only
  // Road plane of the first frame in the world, n . x + d = 0 with n up; from
  // planes/ when present, else through the fitted cars' bottom centres.
  Eigen::Vector4d ground_plane_in_world = Eigen::Vector4d(0, -1, 0, 1.65);
  std::string ground_plane_source;         // "planes/<file>" or "fitted cars"
  std::vector<TrackView> tracks;           // by id
  std::vector<GroundTruthCarView> ground_truth;  // empty without SEQ/gt
  double error_tau = 0.2;                  // τ of the error colouring, m

  const TrackView* FindTrack(int id) const;
};

struct FitRunView {
  std::string output_dir;
  std::string model_path;
  std::vector<SequenceView> sequences;
  int NumTracks() const;
};

struct LoadFitRunOptions {
  bool read_images = true;                 // list left images (for the overlays)
  bool read_ground_truth = true;           // SEQ/gt when present: boxes, error colouring
  double error_tau = 0.2;                  // τ for the error colouring, m (> 0)
  int error_samples = 20000;               // ground-truth surface samples for the errors (> 0)

  void Check() const;
};

// Reads OUT/tracks.json, OUT/meshes/..., and per sequence the directory that
// tracks.json names (calibration, poses, detections or the tracking labels of
// OUT/config.json, planes, image_2, gt/). Only sequences that were fitted are
// returned. Throws samp::Error naming the file and field on missing or
// malformed input.
FitRunView LoadFitRun(const std::string& output_dir, const LoadFitRunOptions& options = {});

// The frame of every point of a track's aligned-points file
// (meshes/track_<id>_points.ply, written with the colour of frame k of n:
// red = 255 k/(n-1), green = 64, blue = 255 (1 - k/(n-1)), truncated).
// Returns -1 for a colour no frame has.
int FrameIndexOfColor(uint8_t red, uint8_t green, uint8_t blue, int num_frames);

}  // namespace samp
