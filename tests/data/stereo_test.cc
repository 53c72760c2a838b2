#include "libsamp/data/stereo.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>

#include "libsamp/core/error.h"
#include "tests/testing/expect_error.h"

namespace samp {
namespace {

StereoCalibration KittiCalibration() {
  StereoCalibration c;  // PinholeCamera defaults are KITTI's
  c.baseline = 0.54;
  return c;
}

TEST(StereoTest, DisparityToPointAndSigma) {
  const StereoCalibration c = KittiCalibration();
  const double f = c.camera.fx, b = c.baseline;
  // d = f b / z: a point at 13 m.
  const double d = f * b / 13.0;
  const Eigen::Vector3d p = DisparityToPoint(c.camera.cx + 100, c.camera.cy - 50, d, c);
  EXPECT_NEAR(p.z(), 13.0, 1e-12);
  EXPECT_NEAR(p.x(), 100 * 13.0 / f, 1e-12);
  EXPECT_NEAR(p.y(), -50 * 13.0 / c.camera.fy, 1e-12);
  EXPECT_TRUE(c.camera.Project(p).isApprox(Eigen::Vector2d(c.camera.cx + 100, c.camera.cy - 50)));
  // sigma_z = z^2 sigma_d / (b f): 13^2 / (0.54 * 721.5377) = 0.43374 m at 1 px.
  EXPECT_NEAR(DepthSigma(13.0, 1.0, c), 169.0 / (0.54 * 721.5377), 1e-12);
  EXPECT_NEAR(DepthSigma(13.0, 1.0, c), 0.43374, 1e-4);
  EXPECT_NEAR(DepthSigma(13.0, 0.5, c), 0.5 * DepthSigma(13.0, 1.0, c), 1e-12);
  // It is the first-order change of z for a 1 px disparity change.
  const double dz = f * b / (d - 1e-4) - f * b / d;
  EXPECT_NEAR(DepthSigma(13.0, 1e-4, c), dz, 1e-6);
}

TEST(StereoTest, DisparityToPointsSkipsInvalidAndHonoursRoi) {
  const StereoCalibration c = KittiCalibration();
  cv::Mat disparity(10, 20, CV_32FC1, cv::Scalar(0));
  disparity.at<float>(2, 3) = 30.0f;
  disparity.at<float>(5, 15) = 0.5f;  // below min
  disparity.at<float>(7, 7) = std::nanf("");
  disparity.at<float>(8, 18) = 10.0f;
  std::vector<StereoPoint> points = DisparityToPoints(disparity, c, 1.0);
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[0].u, 3);
  EXPECT_EQ(points[0].v, 2);
  EXPECT_FLOAT_EQ(points[0].disparity_px, 30.0f);
  EXPECT_NEAR(points[0].point_in_camera.z(), c.camera.fx * c.baseline / 30.0, 1e-9);
  points = DisparityToPoints(disparity, c, 1.0, 1, cv::Rect(10, 0, 100, 100));  // clipped ROI
  ASSERT_EQ(points.size(), 1u);
  EXPECT_EQ(points[0].u, 18);
  EXPECT_EQ(DisparityToPoints(disparity, c, 0.25).size(), 3u);
  EXPECT_THROW(DisparityToPoints(cv::Mat(3, 3, CV_16UC1), c), Error);
}

TEST(StereoTest, OptionsCheck) {
  StereoOptions options;
  EXPECT_NO_THROW(options.Check());
  options.num_disparities = 100;
  test::ExpectError([&] { options.Check(); }, {"StereoOptions.num_disparities"});
  options = StereoOptions();
  options.block_size = 4;
  test::ExpectError([&] { options.Check(); }, {"StereoOptions.block_size"});
  options = StereoOptions();
  options.mode = "fast";
  test::ExpectError([&] { options.Check(); }, {"StereoOptions.mode"});
  options = StereoOptions();
  options.p1 = 100;
  options.p2 = 50;
  test::ExpectError([&] { options.Check(); }, {"StereoOptions.p2"});
}

TEST(StereoTest, SgbmRecoversAShift) {
  // A random texture seen with a constant disparity of 12 px:
  // right(u, v) = left(u + 12, v).
  const int width = 240, height = 100, shift = 12;
  cv::Mat wide(height, width + shift, CV_8UC1);
  cv::RNG rng(7);
  rng.fill(wide, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(wide, wide, cv::Size(3, 3), 0.8);
  const cv::Mat left = wide(cv::Rect(0, 0, width, height)).clone();
  const cv::Mat right = wide(cv::Rect(shift, 0, width, height)).clone();
  // right(u) = wide(u + shift) = left(u + shift)  =>  a left pixel u appears at u - shift.
  StereoOptions options;
  options.num_disparities = 32;
  const cv::Mat disparity = ComputeDisparity(left, right, options);
  ASSERT_EQ(disparity.type(), CV_32FC1);
  ASSERT_EQ(disparity.size(), left.size());
  int valid = 0, good = 0, total = 0;
  for (int v = 10; v < height - 10; ++v)
    for (int u = 50; u < width - 10; ++u) {
      const float d = disparity.at<float>(v, u);
      ++total;
      EXPECT_GE(d, 0.0f);
      if (d > 0) {
        ++valid;
        if (std::abs(d - shift) < 0.5f) ++good;
      }
    }
  EXPECT_GT(valid, 0.9 * total);
  EXPECT_GT(good, 0.95 * valid);
  // Columns u < num_disparities have no full search range: no negative or NaN values there either.
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) ASSERT_TRUE(disparity.at<float>(v, u) >= 0.0f);
  // Colour input works too; mismatched inputs are errors.
  cv::Mat left_bgr, right_bgr;
  cv::cvtColor(left, left_bgr, cv::COLOR_GRAY2BGR);
  cv::cvtColor(right, right_bgr, cv::COLOR_GRAY2BGR);
  EXPECT_EQ(ComputeDisparity(left_bgr, right_bgr, options).size(), left.size());
  EXPECT_THROW(ComputeDisparity(left, right_bgr, options), Error);
  EXPECT_THROW(ComputeDisparity(left, right(cv::Rect(0, 0, 200, 100)), options), Error);
}

}  // namespace
}  // namespace samp
