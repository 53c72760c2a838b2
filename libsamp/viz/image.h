// 8-bit RGB images for samp's pictures (PNG sheets, plots), colour maps, text
// and simple composition. No display is needed. OpenCV does the drawing and
// the PNG encoding behind this header; callers never see cv::Mat.
// Text is drawn with DejaVu Sans through OpenCV's FreeType module when the font
// is installed (Debian: fonts-dejavu-core), else with OpenCV's Hershey font.
// An RgbImage is plain data; the free functions are thread-safe.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace samp {

struct Rgb {
  uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb& o) const { return r == o.r && g == o.g && b == o.b; }
  bool operator!=(const Rgb& o) const { return !(*this == o); }
};

inline constexpr Rgb kWhite{255, 255, 255};
inline constexpr Rgb kBlack{0, 0, 0};
inline constexpr Rgb kDarkGray{64, 64, 64};
inline constexpr Rgb kGray{128, 128, 128};
inline constexpr Rgb kLightGray{220, 220, 220};

struct RgbImage {
  int width = 0, height = 0;
  std::vector<uint8_t> pixels;  // row-major, 3 bytes per pixel in R, G, B order

  RgbImage() = default;
  RgbImage(int width, int height, Rgb fill = kWhite);
  // Takes a row-major RGB buffer of width * height * 3 bytes (e.g. ShadeRender's).
  static RgbImage FromBuffer(int width, int height, std::vector<uint8_t> rgb);

  bool Empty() const { return width <= 0 || height <= 0; }
  Rgb At(int x, int y) const {
    const size_t i = 3 * (size_t(y) * width + x);
    return {pixels[i], pixels[i + 1], pixels[i + 2]};
  }
  void Set(int x, int y, Rgb c) {
    const size_t i = 3 * (size_t(y) * width + x);
    pixels[i] = c.r, pixels[i + 1] = c.g, pixels[i + 2] = c.b;
  }
};

// ---- Files ----------------------------------------------------------------
// Writes a PNG atomically (core/atomic_file.h); creates parent folders.
// Throws samp::Error on an empty image or when encoding/writing fails.
void WritePng(const std::string& path, const RgbImage& image);
// Reads a PNG (or any format OpenCV reads) as RGB; throws samp::Error naming the file.
RgbImage ReadPng(const std::string& path);

// ---- Colour maps (inputs outside the range are clamped to its ends) -------
// Perceptually uniform sequential map (matplotlib's viridis), t in [0, 1].
Rgb Viridis(double t);
// Diverging map for signed fields, t in [-1, 1]: blue (negative, inside) -
// white (0) - red (positive, outside), after ColorBrewer RdBu.
Rgb Diverging(double t);
// Ten distinguishable colours for series and meshes (Tableau 10), cycling.
Rgb PaletteColor(int index);

// Colours a row-major scalar field of width x height values. Sequential:
// Viridis((v - lo) / (hi - lo)). Signed: Diverging(v / max_abs). NaN -> gray.
RgbImage ColorizeSequential(const std::vector<float>& values, int width, int height, double lo,
                            double hi);
RgbImage ColorizeSigned(const std::vector<float>& values, int width, int height, double max_abs);

// ---- Text -----------------------------------------------------------------
enum class HAlign { kLeft, kCenter, kRight };
enum class VAlign { kTop, kMiddle, kBottom };

struct TextStyle {
  double size_px = 14.0;         // cap-to-descender height of the font, pixels
  Rgb color = kBlack;
  bool bold = false;
  HAlign h_align = HAlign::kLeft;
  VAlign v_align = VAlign::kTop;  // vertical anchor of the text's box at (x, y)
  bool vertical = false;          // rotated 90 degrees counter-clockwise (y-axis labels)
};

// The text colour of plots and picture labels.
inline constexpr Rgb kTextGray{40, 40, 40};

// A style in one expression, e.g. MakeTextStyle(12, HAlign::kCenter, VAlign::kMiddle, true).
inline TextStyle MakeTextStyle(double size_px, HAlign h_align = HAlign::kLeft,
                               VAlign v_align = VAlign::kTop, bool bold = false,
                               Rgb color = kTextGray) {
  TextStyle style;
  style.size_px = size_px;
  style.h_align = h_align;
  style.v_align = v_align;
  style.bold = bold;
  style.color = color;
  return style;
}

// Width and height in pixels of `text` drawn with `style` (unrotated).
void MeasureText(const std::string& text, const TextStyle& style, int* width, int* height);
// Draws one line of text anchored at (x, y) as style's alignment says.
void DrawText(RgbImage* image, const std::string& text, int x, int y, const TextStyle& style);

// ---- Drawing and composition -----------------------------------------------
// Anti-aliased line / polyline, `thickness` in pixels.
void DrawLine(RgbImage* image, double x0, double y0, double x1, double y1, Rgb color,
              int thickness = 1);
// Filled (thickness < 0) or outlined rectangle with corners (x0, y0), (x1, y1) inclusive.
void DrawRectangle(RgbImage* image, int x0, int y0, int x1, int y1, Rgb color, int thickness = -1);
// Resampled copy (area averaging when shrinking, bilinear when enlarging).
RgbImage Resize(const RgbImage& image, int width, int height);
// Resized to fit into max_width x max_height keeping the aspect ratio.
RgbImage ResizeToFit(const RgbImage& image, int max_width, int max_height);
// Copies `source` into `*target` with its top-left corner at (x, y), clipped.
void Paste(const RgbImage& source, int x, int y, RgbImage* target);
// The smallest sub-image holding every pixel that differs from `background`,
// grown by `margin` pixels (clipped); the image itself when all is background.
RgbImage CropToContent(const RgbImage& image, Rgb background = kWhite, int margin = 0);

// Mean over channels of the variance of the pixel values (0 for a blank image).
double PixelVariance(const RgbImage& image);

}  // namespace samp
