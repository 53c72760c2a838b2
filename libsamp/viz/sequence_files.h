// Interim readers of the sequence-directory files that the pictures and the
// viewer need (docs/sequence_format.md): the left camera of calib/<seq>.txt,
// poses/, KITTI object and tracking label lines, planes/, and the listing of
// image_2/, detections/, planes/ and gt/. They exist because the one owner of
// these formats (the data layer of issue 10) is not below viz yet; once it is,
// fit_run.cc reads through it and this file goes. Errors name the file and the
// line. Free functions, thread-safe.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "libsamp/core/camera.h"

namespace samp::sequence_files {

struct ObjectLabel {
  int frame = -1, track_id = -1;
  std::string type;
  Eigen::Vector4d box_2d = Eigen::Vector4d::Zero();  // x1 y1 x2 y2, px
  double height = 0, width = 0, length = 0;           // h w l, m
  Eigen::Vector3d position = Eigen::Vector3d::Zero(); // bottom centre, camera frame
  double rotation_y = 0;
};

struct FrameFiles {
  int frame = 0;
  std::string image_left, detections, plane;  // "" when absent
};

struct SequenceFiles {
  std::string name, calibration, poses;       // poses "" when absent
  std::vector<FrameFiles> frames;             // increasing frame numbers
};

// <seq> = the stem of the single calib/*.txt (or the one named like the folder);
// frames = every <seq>_<ff>.png of image_2/ and <seq>_<ff>.txt of detections/.
SequenceFiles ListSequence(const std::string& directory);
// "<name>_<ff><extension>", ff with at least two digits.
std::string FrameFileName(const std::string& name, int frame, const std::string& extension);
// P2 of calib/<seq>.txt as the left camera of the given image size.
PinholeCamera ReadCalibration(const std::string& path, int width, int height);
std::vector<Eigen::Isometry3d> ReadPoses(const std::string& path);
// KITTI object lines (15/16 columns) and tracking lines (17/18 columns).
std::vector<ObjectLabel> ReadLabels(const std::string& path);
std::vector<ObjectLabel> ReadTrackingLabels(const std::string& path);
// planes/ file: the last line's four numbers, normal scaled to unit length and pointing up (-y).
Eigen::Vector4d ReadPlane(const std::string& path);
bool SameObjectType(const std::string& a, const std::string& b);

}  // namespace samp::sequence_files
