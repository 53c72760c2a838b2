// Dense stereo and the geometry of disparities. OpenCV's semi-global block
// matching (StereoSGBM) stands in for libELAS, which the paper used.
// z = fx * b / d;  sigma_z = z^2 * sigma_d / (b * fx)  (first-order propagation
// of a disparity error sigma_d in px).
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "libsamp/data/track.h"

namespace samp {

// Parameters of cv::StereoSGBM (see docs/sequence_format.md). Defaults are
// tuned for KITTI-sized images (1242 x 375).
struct StereoOptions {
  // Smallest disparity searched, px.
  int min_disparity = 0;
  // Number of disparities searched, px; a positive multiple of 16.
  int num_disparities = 128;
  // Matching block side, px; odd, 1..11 (3..11 in practice).
  int block_size = 5;
  // Smoothness penalties for disparity changes of 1 px (P1) and > 1 px (P2),
  // 0 = OpenCV's customary 8 * channels * block^2 and 32 * channels * block^2.
  int p1 = 0;
  int p2 = 0;
  // Maximum left-right consistency difference, px (< 0 disables the check).
  int disp12_max_diff = 1;
  // Clipping of the prefiltered image derivatives.
  int pre_filter_cap = 63;
  // Best cost must beat the second best by this margin, percent.
  int uniqueness_ratio = 10;
  // Connected regions smaller than this (px) with disparity spread above
  // speckle_range are invalidated; 0 disables speckle filtering.
  int speckle_window_size = 100;
  // Maximum disparity spread within a speckle region, px.
  int speckle_range = 2;
  // "sgbm" (5 directions), "hh" (full 8 directions, more memory), "3way" (fast), "hh4".
  std::string mode = "sgbm";

  void Check() const;  // throws samp::Error naming the field
};

// Computes the disparity of the left image from a rectified pair (8-bit, 1 or 3
// channels, same size). Output CV_32FC1 in px, left image size, 0 where SGBM
// found no valid match (never negative, never NaN). Thread-safe.
cv::Mat ComputeDisparity(const cv::Mat& left, const cv::Mat& right, const StereoOptions& options);

// Point in the left camera for pixel (u, v) with disparity d > 0 px.
inline Eigen::Vector3d DisparityToPoint(double u, double v, double disparity_px,
                                        const StereoCalibration& calibration) {
  const PinholeCamera& c = calibration.camera;
  const double z = c.fx * calibration.baseline / disparity_px;
  return Eigen::Vector3d((u - c.cx) * z / c.fx, (v - c.cy) * z / c.fy, z);
}
// Standard deviation of the depth z (m) for a disparity error sigma_disparity_px.
inline double DepthSigma(double depth, double sigma_disparity_px,
                         const StereoCalibration& calibration) {
  return depth * depth * sigma_disparity_px / (calibration.baseline * calibration.camera.fx);
}

// A stereo point in the left camera with its pixel and disparity.
struct StereoPoint {
  Eigen::Vector3d point_in_camera;
  float u = 0, v = 0;         // pixel, px
  float disparity_px = 0;
};

// All valid pixels (disparity >= min_disparity_px) of the region of interest
// (whole image when roi is empty), every `stride`-th row and column, as points.
std::vector<StereoPoint> DisparityToPoints(const cv::Mat& disparity_px,
                                           const StereoCalibration& calibration,
                                           double min_disparity_px = 1.0, int stride = 1,
                                           const cv::Rect& roi = cv::Rect());

}  // namespace samp
