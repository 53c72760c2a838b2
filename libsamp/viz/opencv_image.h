// Internal to libsamp/viz: views of RgbImage as cv::Mat (no copy). Channel order
// is R, G, B, so cv::Scalar colours are (r, g, b). Not part of the public API.
#pragma once

#include <opencv2/core.hpp>

#include "libsamp/viz/image.h"

namespace samp::internal {

inline cv::Mat AsMat(RgbImage* image) {
  return cv::Mat(image->height, image->width, CV_8UC3, image->pixels.data());
}
inline cv::Mat AsMat(const RgbImage& image) {
  return cv::Mat(image.height, image.width, CV_8UC3, const_cast<uint8_t*>(image.pixels.data()));
}
inline cv::Scalar ToScalar(Rgb c) { return cv::Scalar(c.r, c.g, c.b); }
// Deep copy of an 8-bit 3-channel (RGB) Mat.
RgbImage FromMat(const cv::Mat& mat);

}  // namespace samp::internal
