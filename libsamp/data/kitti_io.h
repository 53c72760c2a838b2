// Readers and writers of the KITTI-style files of a sequence directory (see
// docs/sequence_format.md). Every reader throws samp::Error naming the file and
// the line (1-based) of the first problem: missing file, wrong number count,
// a token that is not a number, NaN/inf, a detection behind the camera, a
// disparity PNG of the wrong type or size. Nothing is silently dropped or
// clamped. All writers are atomic (temporary file + rename). Free functions,
// no shared state: thread-safe.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "libsamp/data/track.h"

namespace samp {

// Calibration file: lines "P2: 12 numbers" and "P3: 12 numbers" (3x4 row-major
// projection matrices of the rectified left and right colour cameras); other
// lines are ignored. Intrinsics from P2; baseline = (P2(0,3) - P3(0,3)) / fx.
// Plausibility (an error naming the file, line and value otherwise): every
// number |v| <= kMaxCalibrationValue, focal lengths fx, fy in
// (kMinFocalLengthPx, kMaxFocalLengthPx], baseline in (0, kMaxBaseline], and,
// when the image size is given, the principal point inside the image
// (0 <= cx <= width, 0 <= cy <= height). The file carries no image
// size: the camera gets image_width x image_height; 0 x 0 = not known (KITTI's
// 1242 x 375 is used and the principal point is not checked).
constexpr double kMaxCalibrationValue = 1e9;
constexpr double kMinFocalLengthPx = 1.0;
constexpr double kMaxFocalLengthPx = 1e5;
constexpr double kMaxBaseline = 10.0;  // m
// KITTI stereo 2015's calib_cam_to_cam/<seq>.txt is read too: its
// "P_rect_02:" and "P_rect_03:" lines are P2 and P3.
StereoCalibration ReadCalibration(const std::string& path, int image_width = 0,
                                  int image_height = 0);
// t2 = K^-1 P2[:, 3] of such a file: the left colour camera relative to
// rectified camera 0, the frame of KITTI's labels (data/kitti_tracking.h).
Eigen::Vector3d ReadCamera2Offset(const std::string& path);
// Writes "P2: ..." and "P3: ..." lines for `calibration` (P2 with zero
// translation column, P3(0,3) = -fx * baseline).
void WriteCalibration(const std::string& path, const StereoCalibration& calibration);

// KITTI object label lines, one object per line:
//   type trunc occ alpha x1 y1 x2 y2 h w l x y z ry [score]
// (15 or 16 columns; score defaults to 1). frame = track_id = -1. Blank lines
// are skipped. Rejected: other column counts, non-numbers, non-finite values,
// x2 < x1 or y2 < y1, h/w/l < 0, and z <= 0 (behind the camera) unless the
// type is "DontCare" (KITTI marks those with -1000 coordinates).
std::vector<ObjectLabel> ReadLabels(const std::string& path);
// KITTI tracking label lines: frame track_id type trunc occ alpha x1 y1 x2 y2 h w l x y z ry [score]
// (17 or 18 columns), with the same checks; frame >= 0 and track_id >= -1.
std::vector<ObjectLabel> ReadTrackingLabels(const std::string& path);
// Writers of the two formats; numbers with enough digits to round-trip what
// the tools produce (2D boxes 2 decimals, metric values 4, angles 4, score 4).
// ObjectLabel::type is written verbatim (must be non-empty, no whitespace).
void WriteLabels(const std::string& path, const std::vector<ObjectLabel>& labels);
void WriteTrackingLabels(const std::string& path, const std::vector<ObjectLabel>& labels);
// One line of either format, without newline.
std::string FormatLabel(const ObjectLabel& label);
std::string FormatTrackingLabel(const ObjectLabel& label);

// KITTI road plane file: "# Matrix", "WIDTH 4", "HEIGHT 1", then "a b c d".
// Returns (a, b, c, d) with the normal (a, b, c) scaled to unit length; the
// plane is n . x + d = 0 in the camera of that frame, n pointing up (towards
// -y), so n . x + d is the height of x above the road. A plane whose normal
// points down is flipped and reported at debug level; a normal of zero length,
// tilted more than kMaxPlaneTiltDeg from the camera's vertical (a 53 deg
// road was once accepted) is an error, and so is a normal whose length
// overflows (|(a, b, c)| not finite) and a camera more than kMaxPlaneOffset
// above or below the road (|d| after scaling; a road 5 km below the camera
// once made a label at y = 5,050 m).
constexpr double kMaxPlaneOffset = 10.0;   // m
constexpr double kMaxPlaneTiltDeg = 30.0;  // deg
Eigen::Vector4d ReadPlane(const std::string& path);
void WritePlane(const std::string& path, const Eigen::Vector4d& plane);

// Poses file: one line per frame (frame 0 first), 12 numbers, the 3x4
// row-major matrix [R | t] mapping camera-of-frame coordinates to world.
// R must be a rotation (orthonormal within 1e-3, det > 0) and |t| at most
// kMaxPoseTranslation (an ego pose, not a number's overflow).
constexpr double kMaxPoseTranslation = 1e6;  // m
std::vector<Eigen::Isometry3d> ReadPoses(const std::string& path);
void WritePoses(const std::string& path, const std::vector<Eigen::Isometry3d>& world_from_camera);

// Disparity PNG: single channel uint16, disparity_px = value / 256, 0 = invalid.
// Returns a CV_32FC1 image in pixels with 0 where invalid. Throws when the file
// does not decode, is not 1-channel 16-bit, or (when expected_size is non-empty)
// has another size.
// The memory budget of one decoded image (bytes): ReadImage refuses a PNG
// whose header announces more (width x height x channels x bytes per sample)
// before anything is decoded (a 1.7 MB PNG announcing 30000 x 30000 pixels
// once took 1.8 GB). SequenceOptions::max_image_bytes sets it for sequences.
constexpr int64_t kDefaultMaxImageBytes = int64_t(256) << 20;

// What a PNG file's IHDR chunk announces.
struct PngHeader {
  int64_t width = 0, height = 0;
  int channels = 0;       // after palette expansion: 1, 2, 3 or 4
  int bit_depth = 0;      // 1, 2, 4, 8 or 16
  int64_t DecodedBytes() const { return width * height * channels * (bit_depth > 8 ? 2 : 1); }
};

// Reads and checks the header of the PNG file `path` (signature, IHDR chunk
// length, type, dimensions 1..2^31-1, bit depth and colour type of the PNG
// specification) without decoding it; errors name the file.
PngHeader ReadPngHeader(const std::string& path);

// cv::imread(path, flags) of a PNG after ReadPngHeader and the memory budget
// `max_bytes`; OpenCV's exceptions and an image it cannot decode become
// samp::Error naming the file (`what`: "disparity map", "left image", ...).
cv::Mat ReadImage(const std::string& path, int flags, const char* what,
                  int64_t max_bytes = kDefaultMaxImageBytes);

cv::Mat ReadDisparity(const std::string& path, const cv::Size& expected_size = cv::Size(),
                      int64_t max_bytes = kDefaultMaxImageBytes);
// Writes a CV_32FC1 disparity (px; <= 0 or non-finite = invalid) as such a PNG;
// values are rounded to 1/256 px and must be < 256 px.
void WriteDisparity(const std::string& path, const cv::Mat& disparity_px);

// Case-insensitive type comparison ("car" == "Car").
bool SameObjectType(const std::string& a, const std::string& b);

}  // namespace samp
