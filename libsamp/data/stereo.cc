#include "libsamp/data/stereo.h"

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "libsamp/core/error.h"
#include "libsamp/data/sequence_option_table.h"

namespace samp {
namespace {

int SgbmMode(const std::string& mode) {
  if (mode == "sgbm") return cv::StereoSGBM::MODE_SGBM;
  if (mode == "hh") return cv::StereoSGBM::MODE_HH;
  if (mode == "3way") return cv::StereoSGBM::MODE_SGBM_3WAY;
  if (mode == "hh4") return cv::StereoSGBM::MODE_HH4;
  SAMP_THROW() << "StereoOptions.mode '" << mode << "' must be sgbm, hh, 3way or hh4";
}

}  // namespace

void StereoOptions::Check() const { StereoOptionTable().Check(*this); }

cv::Mat ComputeDisparity(const cv::Mat& left, const cv::Mat& right, const StereoOptions& options) {
  options.Check();
  SAMP_CHECK(!left.empty() && !right.empty()) << "ComputeDisparity: empty image";
  SAMP_CHECK(left.size() == right.size())
      << "ComputeDisparity: left " << left.cols << "x" << left.rows << " and right " << right.cols
      << "x" << right.rows << " images differ in size";
  SAMP_CHECK(left.depth() == CV_8U && right.depth() == CV_8U &&
             left.channels() == right.channels() &&
             (left.channels() == 1 || left.channels() == 3))
      << "ComputeDisparity: images must be 8-bit with 1 or 3 channels, both alike";
  const int channels = left.channels();
  const int area = options.block_size * options.block_size;
  const int p1 = options.p1 > 0 ? options.p1 : 8 * channels * area;
  const int p2 = options.p2 > 0 ? options.p2 : 32 * channels * area;
  cv::Ptr<cv::StereoSGBM> sgbm = cv::StereoSGBM::create(
      options.min_disparity, options.num_disparities, options.block_size, p1, p2,
      options.disp12_max_diff, options.pre_filter_cap, options.uniqueness_ratio,
      options.speckle_window_size, options.speckle_range * 16 /* OpenCV: in 16ths */,
      SgbmMode(options.mode));
  cv::Mat fixed_point;  // CV_16S, disparity * 16, invalid = (min_disparity - 1) * 16
  sgbm->compute(left, right, fixed_point);
  cv::Mat disparity(fixed_point.size(), CV_32FC1);
  for (int r = 0; r < fixed_point.rows; ++r) {
    const int16_t* in = fixed_point.ptr<int16_t>(r);
    float* out = disparity.ptr<float>(r);
    for (int c = 0; c < fixed_point.cols; ++c) {
      const float d = in[c] / 16.0f;
      out[c] = (in[c] >= options.min_disparity * 16 && d > 0) ? d : 0.0f;
    }
  }
  return disparity;
}

std::vector<StereoPoint> DisparityToPoints(const cv::Mat& disparity_px,
                                           const StereoCalibration& calibration,
                                           double min_disparity_px, int stride,
                                           const cv::Rect& roi) {
  SAMP_CHECK(disparity_px.type() == CV_32FC1) << "DisparityToPoints: expected a CV_32FC1 disparity";
  SAMP_CHECK(stride >= 1) << "DisparityToPoints: stride " << stride << " must be >= 1";
  SAMP_CHECK(calibration.baseline > 0 && calibration.camera.fx > 0)
      << "DisparityToPoints: calibration without baseline or focal length";
  const cv::Rect image(0, 0, disparity_px.cols, disparity_px.rows);
  const cv::Rect region = roi.empty() ? image : (roi & image);
  const double min_d = std::max(min_disparity_px, 1e-6);
  std::vector<StereoPoint> points;
  for (int v = region.y; v < region.y + region.height; v += stride) {
    const float* row = disparity_px.ptr<float>(v);
    for (int u = region.x; u < region.x + region.width; u += stride) {
      const float d = row[u];
      if (!(d >= min_d)) continue;  // also skips NaN
      StereoPoint point;
      point.point_in_camera = DisparityToPoint(u, v, d, calibration);
      point.u = static_cast<float>(u);
      point.v = static_cast<float>(v);
      point.disparity_px = d;
      points.push_back(point);
    }
  }
  return points;
}

}  // namespace samp
