// KITTI tracking's own layout (docs/sequence_format.md, "KITTI tracking"):
// its paths, its calibration file, its GPS/IMU (oxts) file and the ego poses
// computed from them. The owner of these formats: reader and writer.
//
//   ROOT/image_02/<seq>/<ffffff>.png   left colour image (rectified camera 2)
//   ROOT/image_03/<seq>/<ffffff>.png   right colour image (rectified camera 3)
//   ROOT/calib/<seq>.txt               P0..P3, R_rect, Tr_velo_cam, Tr_imu_velo
//   ROOT/oxts/<seq>.txt                one GPS/IMU record (30 numbers) per frame
//   ROOT/label_02/<seq>.txt            ground-truth tracking labels (training)
//
// ROOT is KITTI's `training` (or `testing`) folder, <seq> four digits ("0004").
//
// Frames. KITTI's labels and detections are given in the *rectified camera 0*
// frame (x right, y down, z forward); the stereo points of image_02/image_03
// are in the *rectified camera 2* frame, which differs from it by the
// translation t2 = K^-1 P2[:, 3] (P2 = K [I | t2]; about 6 cm along x in
// KITTI). samp's in-memory sequence uses camera 2 (the camera of its stereo
// points and 2D boxes): a label read from a KITTI file is moved by +t2, and a
// fitted label written for KITTI is moved back by -t2 (MoveLabel).
//
// Ego poses from oxts (the KITTI devkit's conventions, written out here):
//   * Mercator scale s = cos(lat_0 pi / 180), lat_0 the first record's latitude.
//   * Position of record k, metres (x east, y north, z up), with the
//     equatorial radius r = 6378137 m:
//       x_k = s r lon_k pi / 180,  y_k = s r ln tan((90 + lat_k) pi / 360),  z_k = alt_k.
//   * Orientation R_k = Rz(yaw_k) Ry(pitch_k) Rx(roll_k) (angles in radians):
//     mercator_from_imu_k = [R_k | (x_k, y_k, z_k)].
//   * IMU poses relative to the first record:
//       imu0_from_imu_k = mercator_from_imu_0^-1 mercator_from_imu_k.
//   * The IMU -> rectified camera 2 chain of the calibration file:
//       C = cam2_from_rect0 * R_rect * Tr_velo_cam * Tr_imu_velo
//     (Tr_imu_velo: IMU -> velodyne, Tr_velo_cam: velodyne -> camera 0,
//      R_rect: camera 0 -> rectified camera 0, cam2_from_rect0: + t2).
//   * world_from_camera_k = C imu0_from_imu_k C^-1: the world is rectified
//     camera 2 of frame 0 (x right, y down, z forward at frame 0).
// The inverse (OxtsFromCameraPoses) places camera 2 of frame 0 at a chosen
// latitude, longitude, altitude and heading and inverts each step (inverse
// Mercator with the same scale; ZYX Euler angles of R_k).
//
// Every reader throws samp::Error naming the file and line of the first
// problem; writers are atomic. Free functions: thread-safe.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

#include "libsamp/data/track.h"

namespace samp {

// Paths of one sequence in KITTI tracking's layout. A value type.
class KittiTrackingLayout {
 public:
  static constexpr const char* kLeftImageFolder = "image_02";
  static constexpr const char* kRightImageFolder = "image_03";
  static constexpr const char* kCalibrationFolder = "calib";
  static constexpr const char* kOxtsFolder = "oxts";
  static constexpr const char* kLabelFolder = "label_02";

  KittiTrackingLayout(std::string root, std::string name);

  const std::string& root() const { return root_; }
  const std::string& name() const { return name_; }

  std::string LeftImageFolder() const;      // ROOT/image_02/<seq>
  std::string RightImageFolder() const;     // ROOT/image_03/<seq>
  std::string LeftImage(int frame) const;   // ROOT/image_02/<seq>/<ffffff>.png
  std::string RightImage(int frame) const;  // ROOT/image_03/<seq>/<ffffff>.png
  std::string Calibration() const;          // ROOT/calib/<seq>.txt
  std::string Oxts() const;                 // ROOT/oxts/<seq>.txt
  std::string Labels() const;               // ROOT/label_02/<seq>.txt

  // "<ffffff>.png": six digits.
  static std::string FrameFileName(int frame, const std::string& extension);
  // The frame of a file named "<digits><extension>" (at most 6 digits), else -1.
  static int FrameOfFileName(const std::string& path, const std::string& extension);
  // Whether `folder` is a sequence folder ROOT/image_02/<seq> of this layout
  // (its parent is named image_02 and it has no calib/ folder of samp's
  // layout); fills *layout when so. Nothing but the names is checked.
  static bool FromSequenceFolder(const std::string& folder, KittiTrackingLayout* layout);

 private:
  std::string root_;
  std::string name_;
};

// The sequence folders ROOT/image_02/<seq> of `sequences`: "all" (every folder
// of ROOT/image_02, sorted) or a comma-separated list of names ("0004,0011";
// a number of fewer than four digits is padded: "4" -> "0004"). Throws naming
// ROOT and the sequence when a folder does not exist.
std::vector<std::string> KittiTrackingSequenceFolders(const std::string& root, const std::string& sequences);

// The calibration file of a KITTI tracking sequence. Keys with or without the
// colon, and the object benchmark's names too: P0..P3 (12 numbers each),
// R_rect / R0_rect (9), Tr_velo_cam / Tr_velo_to_cam (12), Tr_imu_velo /
// Tr_imu_to_velo (12). Every key is required (an error naming the file and
// the key otherwise); rotations must be orthonormal within 1e-3 and are
// re-orthonormalised (SVD).
struct KittiTrackingCalibration {
  std::array<Eigen::Matrix<double, 3, 4>, 4> p;  // P0..P3, rectified projections
  Eigen::Matrix3d rect = Eigen::Matrix3d::Identity();                   // R_rect: camera 0 -> rectified
  Eigen::Isometry3d cam0_from_velo = Eigen::Isometry3d::Identity();    // Tr_velo_cam
  Eigen::Isometry3d velo_from_imu = Eigen::Isometry3d::Identity();     // Tr_imu_velo

  // t2 = K^-1 P2[:, 3]: rectified camera 2 = rectified camera 0 + t2.
  Eigen::Vector3d Camera2FromRectified0() const;
  // C = cam2_from_rect0 * R_rect * Tr_velo_cam * Tr_imu_velo.
  Eigen::Isometry3d Camera2FromImu() const;
};
KittiTrackingCalibration ReadKittiTrackingCalibration(const std::string& path);
// A calibration like KITTI's for the rectified stereo pair `stereo` (camera 2
// = left, camera 3 = right): camera 2 at t2 = (0.06, 0, 0.0027) m from
// rectified camera 0, camera 1 `stereo.baseline` right of camera 0, R_rect a
// 0.5 deg rotation, the velodyne 27 cm behind and 8 cm above camera 0 (axes
// x forward, y left, z up), the IMU 0.81 m behind, 0.32 m left of and 0.80 m
// below the velodyne. What `samp synth --layout kitti-tracking` writes.
KittiTrackingCalibration MakeKittiTrackingCalibration(const StereoCalibration& stereo);
// Writes the tracking benchmark's form ("P0: ...", "R_rect ...", "Tr_velo_cam ...",
// "Tr_imu_velo ..."), numbers with 17 significant digits.
void WriteKittiTrackingCalibration(const std::string& path, const KittiTrackingCalibration& calibration);

// One line of an oxts file: lat lon alt roll pitch yaw, then 24 more numbers
// (velocities, accelerations, angular rates, accuracies, status; samp reads
// only the first six). Degrees, metres, radians.
struct OxtsRecord {
  double lat_deg = 0.0, lon_deg = 0.0, alt = 0.0;
  double roll = 0.0, pitch = 0.0, yaw = 0.0;
  std::array<double, 24> rest{};
};
// Line k is frame k. Rejected (path:line): other than 30 numbers, non-finite
// values, |lat| > 85 deg (Mercator), |lon| > 180 deg, |alt| > 1e4 m, an angle
// beyond +-2 pi, a blank line before the last record.
std::vector<OxtsRecord> ReadOxts(const std::string& path);
// Numbers with 17 significant digits: the round trip is exact to ~1e-10 m.
// (With 15 digits poses are off by ~1e-8 m, and in a test the fit turned
// that into a 0.03 deg different yaw of one car: tests/eval/kitti_tracking_layout_test.cc.)
void WriteOxts(const std::string& path, const std::vector<OxtsRecord>& records);

// imu0_from_imu_k of every record (see the maths above); empty for no records.
std::vector<Eigen::Isometry3d> ImuPosesFromOxts(const std::vector<OxtsRecord>& records);
// world_from_camera_k, world = rectified camera 2 of record 0.
std::vector<Eigen::Isometry3d> CameraPosesFromOxts(const std::vector<OxtsRecord>& records,
                                                   const KittiTrackingCalibration& calibration);

// Where the first record is: its position and the IMU's orientation.
struct OxtsOrigin {
  double lat_deg = 49.0112;   // Karlsruhe, as KITTI
  double lon_deg = 8.4229;
  double alt = 112.8;
  double roll = 0.0, pitch = 0.0, yaw = 0.5;  // radians
};
// Records whose CameraPosesFromOxts are `world_from_camera` up to the choice
// of world (camera 2 of frame 0 then). The velocities (ve vn vf vl vu) are
// finite differences of the positions; accelerations and angular rates are 0;
// accuracies and status fields are constants of a good fix. Throws when a
// pose is not rigid or its pitch reaches +-90 deg.
std::vector<OxtsRecord> OxtsFromCameraPoses(const std::vector<Eigen::Isometry3d>& world_from_camera,
                                            const KittiTrackingCalibration& calibration,
                                            const OxtsOrigin& origin, double frame_rate_hz);

// `label` moved by `offset` (position + offset) with alpha recomputed for the
// new position (alpha = ry - atan2(x, z), wrapped to (-pi, pi]); a zero
// offset returns the label unchanged.
ObjectLabel MoveLabel(const ObjectLabel& label, const Eigen::Vector3d& offset);

}  // namespace samp
