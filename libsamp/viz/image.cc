#include "libsamp/viz/image.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#ifdef SAMP_HAVE_FREETYPE
#include <opencv2/freetype.hpp>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <mutex>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/viz/opencv_image.h"

namespace samp {

namespace internal {
RgbImage FromMat(const cv::Mat& mat) {
  SAMP_CHECK(mat.type() == CV_8UC3) << "FromMat: expected an 8-bit 3-channel image";
  RgbImage image(mat.cols, mat.rows);
  cv::Mat view = AsMat(&image);
  mat.copyTo(view);
  return image;
}
}  // namespace internal

using internal::AsMat;
using internal::ToScalar;

RgbImage::RgbImage(int width_in, int height_in, Rgb fill) : width(width_in), height(height_in) {
  SAMP_CHECK(width >= 0 && height >= 0) << "RgbImage: negative size " << width << "x" << height;
  pixels.resize(size_t(width) * height * 3);
  for (size_t i = 0; i < pixels.size(); i += 3) {
    pixels[i] = fill.r, pixels[i + 1] = fill.g, pixels[i + 2] = fill.b;
  }
}

RgbImage RgbImage::FromBuffer(int width, int height, std::vector<uint8_t> rgb) {
  SAMP_CHECK(width >= 0 && height >= 0) << "RgbImage: negative size " << width << "x" << height;
  SAMP_CHECK(rgb.size() == size_t(width) * height * 3)
      << "RgbImage: buffer of " << rgb.size() << " bytes for a " << width << "x" << height
      << " RGB image";
  RgbImage image;
  image.width = width;
  image.height = height;
  image.pixels = std::move(rgb);
  return image;
}

// ---- Files ----------------------------------------------------------------

void WritePng(const std::string& path, const RgbImage& image) {
  SAMP_CHECK(!image.Empty()) << "cannot write " << path << ": empty image";
  cv::Mat bgr;
  cv::cvtColor(AsMat(image), bgr, cv::COLOR_RGB2BGR);
  // Encoded in memory, then written with every byte checked (cv::imwrite
  // does not report a full disk).
  std::vector<uchar> buffer;
  bool ok = false;
  try {
    ok = cv::imencode(".png", bgr, buffer, {cv::IMWRITE_PNG_COMPRESSION, 6});
  } catch (const cv::Exception& e) {
    SAMP_THROW() << "cannot write " << path << ": " << e.what();
  }
  SAMP_CHECK(ok) << "cannot write " << path << " (OpenCV could not encode it)";
  WriteBytesAtomically(path, std::string(reinterpret_cast<const char*>(buffer.data()), buffer.size()));
}

RgbImage ReadPng(const std::string& path) {
  std::error_code ec;
  SAMP_CHECK(std::filesystem::is_regular_file(path, ec)) << "cannot read " << path
                                                         << ": no such file";
  const cv::Mat bgr = cv::imread(path, cv::IMREAD_COLOR);
  SAMP_CHECK(!bgr.empty()) << "cannot read " << path << ": not an image OpenCV can decode";
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  return internal::FromMat(rgb);
}

// ---- Colour maps ------------------------------------------------------------
namespace {

template <size_t N>
Rgb Interpolate(const std::array<Rgb, N>& stops, double t) {
  if (!(t > 0.0)) t = 0.0;  // also NaN
  if (t > 1.0) t = 1.0;
  const double x = t * (N - 1);
  const size_t i = std::min(size_t(x), N - 2);
  const double f = x - double(i);
  auto mix = [f](uint8_t a, uint8_t b) { return uint8_t(std::lround(a + f * (double(b) - a))); };
  return {mix(stops[i].r, stops[i + 1].r), mix(stops[i].g, stops[i + 1].g),
          mix(stops[i].b, stops[i + 1].b)};
}

// matplotlib's viridis at t = 0, 1/8, ..., 1.
constexpr std::array<Rgb, 9> kViridis = {{{68, 1, 84},
                                          {72, 40, 120},
                                          {62, 73, 137},
                                          {49, 104, 142},
                                          {38, 130, 142},
                                          {31, 158, 137},
                                          {53, 183, 121},
                                          {109, 205, 89},
                                          {253, 231, 37}}};
// ColorBrewer RdBu (11 classes), from blue (negative) to red (positive).
constexpr std::array<Rgb, 11> kBlueWhiteRed = {{{5, 48, 97},
                                                {33, 102, 172},
                                                {67, 147, 195},
                                                {146, 197, 222},
                                                {209, 229, 240},
                                                {247, 247, 247},
                                                {253, 219, 199},
                                                {244, 165, 130},
                                                {214, 96, 77},
                                                {178, 24, 43},
                                                {103, 0, 31}}};
// Tableau 10.
constexpr std::array<Rgb, 10> kPalette = {{{78, 121, 167},
                                           {242, 142, 43},
                                           {225, 87, 89},
                                           {118, 183, 178},
                                           {89, 161, 79},
                                           {237, 201, 72},
                                           {176, 122, 161},
                                           {255, 157, 167},
                                           {156, 117, 95},
                                           {186, 176, 172}}};

}  // namespace

Rgb Viridis(double t) { return Interpolate(kViridis, t); }

Rgb Diverging(double t) { return Interpolate(kBlueWhiteRed, 0.5 * (t + 1.0)); }

Rgb PaletteColor(int index) {
  const int n = int(kPalette.size());
  return kPalette[size_t(((index % n) + n) % n)];
}

RgbImage ColorizeSequential(const std::vector<float>& values, int width, int height, double lo,
                            double hi) {
  SAMP_CHECK(values.size() == size_t(width) * height)
      << "ColorizeSequential: " << values.size() << " values for " << width << "x" << height;
  SAMP_CHECK(hi > lo) << "ColorizeSequential: empty range [" << lo << ", " << hi << "]";
  RgbImage image(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const float v = values[size_t(y) * width + x];
      image.Set(x, y, std::isnan(v) ? kGray : Viridis((v - lo) / (hi - lo)));
    }
  }
  return image;
}

RgbImage ColorizeSigned(const std::vector<float>& values, int width, int height, double max_abs) {
  SAMP_CHECK(values.size() == size_t(width) * height)
      << "ColorizeSigned: " << values.size() << " values for " << width << "x" << height;
  SAMP_CHECK(max_abs > 0) << "ColorizeSigned: max_abs must be positive, got " << max_abs;
  RgbImage image(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const float v = values[size_t(y) * width + x];
      image.Set(x, y, std::isnan(v) ? kGray : Diverging(v / max_abs));
    }
  }
  return image;
}

// ---- Text -------------------------------------------------------------------
namespace {

// Fraction of the font size above the baseline (cap height plus a little).
constexpr double kAscent = 0.76;

class TextRenderer {
 public:
  static TextRenderer& Get() {
    static TextRenderer renderer;
    return renderer;
  }

  // Renders white-on-black text into a single-channel coverage mask, the box
  // [0, width) x [0, height) with the baseline at kAscent * size.
  cv::Mat Render(const std::string& text, double size_px, bool bold) {
    std::lock_guard<std::mutex> lock(mutex_);
    const int height = std::max(1, int(std::ceil(size_px)));
    const int baseline = int(std::lround(kAscent * size_px));
    const int width = std::max(1, WidthLocked(text, size_px, bold));
    cv::Mat canvas(height, width, CV_8UC3, cv::Scalar(0, 0, 0));
#ifdef SAMP_HAVE_FREETYPE
    cv::freetype::FreeType2* font = bold && bold_ ? bold_.get() : regular_.get();
    if (font != nullptr) {
      font->putText(canvas, text, cv::Point(0, baseline), int(std::lround(size_px)),
                    cv::Scalar(255, 255, 255), -1, cv::LINE_AA, /*bottomLeftOrigin=*/true);
    } else
#endif
    {
      cv::putText(canvas, text, cv::Point(0, baseline), cv::FONT_HERSHEY_SIMPLEX,
                  HersheyScale(size_px), cv::Scalar(255, 255, 255), bold ? 2 : 1, cv::LINE_AA);
    }
    cv::Mat mask;
    cv::extractChannel(canvas, mask, 0);
    return mask;
  }

  int Width(const std::string& text, double size_px, bool bold) {
    std::lock_guard<std::mutex> lock(mutex_);
    return WidthLocked(text, size_px, bold);
  }

 private:
  TextRenderer() {
#ifdef SAMP_HAVE_FREETYPE
    regular_ = Load({"/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
                     "/usr/share/fonts/TTF/DejaVuSans.ttf",
                     "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf"});
    bold_ = Load({"/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf",
                  "/usr/share/fonts/TTF/DejaVuSans-Bold.ttf",
                  "/usr/share/fonts/truetype/liberation/LiberationSans-Bold.ttf"});
    if (!regular_) LogDebug() << "no TrueType font found; text uses OpenCV's Hershey font";
#endif
  }

#ifdef SAMP_HAVE_FREETYPE
  static cv::Ptr<cv::freetype::FreeType2> Load(const std::vector<std::string>& candidates) {
    for (const auto& path : candidates) {
      std::error_code ec;
      if (!std::filesystem::is_regular_file(path, ec)) continue;
      try {
        auto font = cv::freetype::createFreeType2();
        font->loadFontData(path, 0);
        return font;
      } catch (const cv::Exception&) {
      }
    }
    return nullptr;
  }
#endif

  static double HersheyScale(double size_px) { return kAscent * size_px / 22.0; }

  int WidthLocked(const std::string& text, double size_px, bool bold) {
    if (text.empty()) return 0;
    int baseline = 0;
#ifdef SAMP_HAVE_FREETYPE
    cv::freetype::FreeType2* font = bold && bold_ ? bold_.get() : regular_.get();
    if (font != nullptr) {
      // Advance-based width plus a pixel for anti-aliasing.
      return font->getTextSize(text, int(std::lround(size_px)), -1, &baseline).width + 2;
    }
#endif
    return cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, HersheyScale(size_px), bold ? 2 : 1,
                           &baseline)
               .width +
           2;
  }

  std::mutex mutex_;
#ifdef SAMP_HAVE_FREETYPE
  cv::Ptr<cv::freetype::FreeType2> regular_, bold_;
#endif
};

}  // namespace

void MeasureText(const std::string& text, const TextStyle& style, int* width, int* height) {
  if (width != nullptr) *width = TextRenderer::Get().Width(text, style.size_px, style.bold);
  if (height != nullptr) *height = std::max(1, int(std::ceil(style.size_px)));
}

void DrawText(RgbImage* image, const std::string& text, int x, int y, const TextStyle& style) {
  SAMP_CHECK(image != nullptr) << "DrawText: null image";
  if (text.empty() || image->Empty()) return;
  SAMP_CHECK(style.size_px > 0) << "DrawText: size_px must be positive";
  cv::Mat mask = TextRenderer::Get().Render(text, style.size_px, style.bold);
  if (style.vertical) cv::rotate(mask, mask, cv::ROTATE_90_COUNTERCLOCKWISE);
  int left = x, top = y;
  switch (style.h_align) {
    case HAlign::kLeft: break;
    case HAlign::kCenter: left = x - mask.cols / 2; break;
    case HAlign::kRight: left = x - mask.cols; break;
  }
  switch (style.v_align) {
    case VAlign::kTop: break;
    case VAlign::kMiddle: top = y - mask.rows / 2; break;
    case VAlign::kBottom: top = y - mask.rows; break;
  }
  for (int r = 0; r < mask.rows; ++r) {
    const int py = top + r;
    if (py < 0 || py >= image->height) continue;
    const uint8_t* row = mask.ptr<uint8_t>(r);
    for (int c = 0; c < mask.cols; ++c) {
      const int px = left + c;
      if (px < 0 || px >= image->width || row[c] == 0) continue;
      const double a = row[c] / 255.0;
      const Rgb old = image->At(px, py);
      auto mix = [a](uint8_t under, uint8_t over) {
        return uint8_t(std::lround(a * over + (1.0 - a) * under));
      };
      image->Set(px, py, {mix(old.r, style.color.r), mix(old.g, style.color.g),
                          mix(old.b, style.color.b)});
    }
  }
}

// ---- Drawing and composition --------------------------------------------------

void DrawLine(RgbImage* image, double x0, double y0, double x1, double y1, Rgb color,
              int thickness) {
  SAMP_CHECK(image != nullptr) << "DrawLine: null image";
  if (image->Empty()) return;
  // Sub-pixel precision: 4 fractional bits.
  constexpr int kShift = 4;
  constexpr double kScale = 1 << kShift;
  cv::Mat mat = AsMat(image);
  cv::line(mat, cv::Point(int(std::lround(x0 * kScale)), int(std::lround(y0 * kScale))),
           cv::Point(int(std::lround(x1 * kScale)), int(std::lround(y1 * kScale))),
           ToScalar(color), std::max(1, thickness), cv::LINE_AA, kShift);
}

void DrawRectangle(RgbImage* image, int x0, int y0, int x1, int y1, Rgb color, int thickness) {
  SAMP_CHECK(image != nullptr) << "DrawRectangle: null image";
  if (image->Empty()) return;
  cv::Mat mat = AsMat(image);
  cv::rectangle(mat, cv::Point(x0, y0), cv::Point(x1, y1), ToScalar(color),
                thickness < 0 ? cv::FILLED : thickness, cv::LINE_8);
}

RgbImage Resize(const RgbImage& image, int width, int height) {
  SAMP_CHECK(!image.Empty()) << "Resize: empty image";
  SAMP_CHECK(width > 0 && height > 0) << "Resize: bad target size " << width << "x" << height;
  if (width == image.width && height == image.height) return image;
  RgbImage result(width, height);
  cv::Mat target = AsMat(&result);
  const bool shrink = width < image.width && height < image.height;
  cv::resize(AsMat(image), target, cv::Size(width, height), 0, 0,
             shrink ? cv::INTER_AREA : cv::INTER_LINEAR);
  return result;
}

RgbImage ResizeToFit(const RgbImage& image, int max_width, int max_height) {
  SAMP_CHECK(!image.Empty()) << "ResizeToFit: empty image";
  const double scale = std::min(double(max_width) / image.width, double(max_height) / image.height);
  return Resize(image, std::max(1, int(std::lround(image.width * scale))),
                std::max(1, int(std::lround(image.height * scale))));
}

void Paste(const RgbImage& source, int x, int y, RgbImage* target) {
  SAMP_CHECK(target != nullptr) << "Paste: null target";
  const int x0 = std::max(0, x), y0 = std::max(0, y);
  const int x1 = std::min(target->width, x + source.width);
  const int y1 = std::min(target->height, y + source.height);
  for (int py = y0; py < y1; ++py) {
    const uint8_t* from = &source.pixels[3 * (size_t(py - y) * source.width + (x0 - x))];
    uint8_t* to = &target->pixels[3 * (size_t(py) * target->width + x0)];
    std::copy(from, from + 3 * (x1 - x0), to);
  }
}

RgbImage CropToContent(const RgbImage& image, Rgb background, int margin) {
  int x0 = image.width, y0 = image.height, x1 = -1, y1 = -1;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      if (image.At(x, y) != background) {
        x0 = std::min(x0, x), x1 = std::max(x1, x);
        y0 = std::min(y0, y), y1 = std::max(y1, y);
      }
    }
  }
  if (x1 < 0) return image;
  x0 = std::max(0, x0 - margin), y0 = std::max(0, y0 - margin);
  x1 = std::min(image.width - 1, x1 + margin), y1 = std::min(image.height - 1, y1 + margin);
  RgbImage result(x1 - x0 + 1, y1 - y0 + 1);
  Paste(image, -x0, -y0, &result);
  return result;
}

double PixelVariance(const RgbImage& image) {
  if (image.Empty()) return 0.0;
  double sum[3] = {0, 0, 0}, sum_sq[3] = {0, 0, 0};
  const size_t n = size_t(image.width) * image.height;
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      const double v = image.pixels[3 * i + c];
      sum[c] += v;
      sum_sq[c] += v * v;
    }
  }
  double variance = 0.0;
  for (int c = 0; c < 3; ++c) {
    const double mean = sum[c] / n;
    variance += sum_sq[c] / n - mean * mean;
  }
  return std::max(0.0, variance / 3.0);
}

}  // namespace samp
