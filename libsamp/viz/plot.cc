#include "libsamp/viz/plot.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "libsamp/core/error.h"
#include "libsamp/viz/opencv_image.h"

namespace samp {

using internal::AsMat;
using internal::ToScalar;

// ---- Ticks -------------------------------------------------------------------

std::vector<double> NiceTicks(double lo, double hi, int max_ticks) {
  SAMP_CHECK(std::isfinite(lo) && std::isfinite(hi) && hi > lo)
      << "NiceTicks: bad range [" << lo << ", " << hi << "]";
  SAMP_CHECK(max_ticks >= 2) << "NiceTicks: max_ticks must be >= 2, got " << max_ticks;
  const double raw_step = (hi - lo) / (max_ticks - 1);
  int exponent = int(std::floor(std::log10(raw_step)));
  static constexpr std::array<double, 5> kMantissas = {1.0, 2.0, 2.5, 5.0, 10.0};
  for (int attempt = 0; attempt < 4; ++attempt, ++exponent) {
    // Ticks are (index * mantissa) scaled by 10^exponent, dividing for negative
    // exponents so that decimal ticks are the doubles nearest to their decimals.
    const double power = std::pow(10.0, std::abs(exponent));
    auto scale = [&](double v) { return exponent >= 0 ? v * power : v / power; };
    for (double mantissa : kMantissas) {
      const double step = scale(mantissa);
      const double first = std::floor(lo / step + 1e-9);
      const double last = std::ceil(hi / step - 1e-9);
      const int count = int(std::lround(last - first)) + 1;
      if (count <= max_ticks) {
        std::vector<double> ticks;
        for (int i = 0; i < count; ++i) {
          double t = scale((first + i) * mantissa);
          if (t == 0.0) t = 0.0;  // no "-0"
          ticks.push_back(t);
        }
        return ticks;
      }
    }
  }
  return {lo, hi};
}

std::string FormatTick(double value, double step) {
  char buffer[64];
  step = std::abs(step);
  if (step > 0 && (step < 1e-4 || std::abs(value) >= 1e6)) {
    std::snprintf(buffer, sizeof(buffer), "%g", value);
    return buffer;
  }
  int decimals = 0;
  while (decimals < 8) {
    const double scaled = step * std::pow(10.0, decimals);
    if (std::abs(scaled - std::round(scaled)) < 1e-6 * std::max(1.0, scaled)) break;
    ++decimals;
  }
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  std::string text = buffer;
  if (text.find_first_not_of("-0.") == std::string::npos && text[0] == '-') text.erase(0, 1);
  return text;
}

namespace {

// All drawing happens at kSupersample x the output size, then is shrunk.
constexpr int kSupersample = 2;
constexpr Rgb kAxisColor{90, 90, 90};
constexpr Rgb kGridColor{232, 232, 232};
// Automatic line-plot ranges leave this share of the data range free at each end.
constexpr double kDataPadding = 0.03;

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void Add(double v) {
    if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  }
  bool Valid() const { return lo <= hi; }
};

// Resolves an axis: the given limits, else the data range padded by
// `pad_fraction` of its length (not across 0) and widened to its ticks.
void ResolveAxis(const Range& data, std::optional<double> given_lo, std::optional<double> given_hi,
                 int max_ticks, const char* axis, double* lo, double* hi,
                 std::vector<double>* ticks, double pad_fraction = 0.0) {
  double a = given_lo ? *given_lo : data.lo;
  double b = given_hi ? *given_hi : data.hi;
  if (data.Valid() && data.hi > data.lo && pad_fraction > 0) {
    const double pad = pad_fraction * (data.hi - data.lo);
    if (!given_lo) a = data.lo >= 0 ? std::max(0.0, a - pad) : a - pad;
    if (!given_hi) b = data.hi <= 0 ? std::min(0.0, b + pad) : b + pad;
  }
  SAMP_CHECK(std::isfinite(a) && std::isfinite(b))
      << "plot: no finite data for the " << axis << " axis and no range given";
  if (given_lo && given_hi) {
    SAMP_CHECK(b > a) << "plot: " << axis << " range is empty: [" << a << ", " << b << "]";
  }
  if (b <= a) {  // a single value: widen symmetrically (or on the free side)
    const double pad = a == 0.0 ? 1.0 : 0.1 * std::abs(a);
    if (!given_lo) a -= pad;
    if (!given_hi) b += pad;
    if (b <= a) b = a + pad;
  }
  const std::vector<double> nice = NiceTicks(a, b, max_ticks);
  if (!given_lo) a = nice.front();
  if (!given_hi) b = nice.back();
  ticks->clear();
  const double eps = 1e-9 * (b - a);
  for (double t : nice) {
    if (t >= a - eps && t <= b + eps) ticks->push_back(t);
  }
  *lo = a, *hi = b;
}

double TickStep(const std::vector<double>& ticks) {
  return ticks.size() >= 2 ? ticks[1] - ticks[0] : 1.0;
}

// A plotting frame: the canvas, the plot rectangle and the value-to-pixel maps.
struct Frame {
  RgbImage canvas;
  int left = 0, top = 0, right = 0, bottom = 0;  // plot rectangle, canvas pixels
  int legend_band_top = 0;                        // first row of a legend above the plot
  double x_lo = 0, x_hi = 1, y_lo = 0, y_hi = 1;
  double font = 15.0;                             // tick font size, canvas pixels

  double Px(double x) const { return left + (x - x_lo) / (x_hi - x_lo) * (right - left); }
  double Py(double y) const { return bottom - (y - y_lo) / (y_hi - y_lo) * (bottom - top); }
};

struct AxisText {
  std::string title, x_label, y_label;
  std::vector<double> x_ticks, y_ticks;
  std::vector<std::string> x_tick_labels;  // overrides formatted x ticks (bar categories)
  bool vertical_x_labels = false;
  bool grid = true;
  bool x_grid = true;
  double font_px = 15.0;                   // output pixels
};


int TextWidth(const std::string& text, double size, bool bold = false) {
  TextStyle style;
  style.size_px = size;
  style.bold = bold;
  int width = 0;
  MeasureText(text, style, &width, nullptr);
  return width;
}

constexpr int kPad = 12 * kSupersample, kTickLength = 5 * kSupersample, kGap = 5 * kSupersample;

std::vector<std::string> YTickLabels(const AxisText& text) {
  std::vector<std::string> labels;
  for (double t : text.y_ticks) labels.push_back(FormatTick(t, TickStep(text.y_ticks)));
  return labels;
}

std::vector<std::string> XTickLabels(const AxisText& text) {
  if (!text.x_tick_labels.empty()) return text.x_tick_labels;
  std::vector<std::string> labels;
  for (double t : text.x_ticks) labels.push_back(FormatTick(t, TickStep(text.x_ticks)));
  return labels;
}

// Places the plot rectangle inside a width x height (output pixels) image,
// leaving room for the title, a legend band of `legend_band` canvas pixels,
// tick labels and axis labels. Allocates the (supersampled) canvas.
void Layout(const AxisText& text, int width, int height, int legend_band, Frame* frame) {
  const int s = kSupersample;
  const double font = text.font_px * s;
  const double label_font = (text.font_px + 1) * s;
  const double title_font = (text.font_px + 4) * s;
  frame->font = font;
  frame->canvas = RgbImage(width * s, height * s, kWhite);

  int y_label_width = 0;
  for (const auto& l : YTickLabels(text)) y_label_width = std::max(y_label_width, TextWidth(l, font));
  const std::vector<std::string> x_labels = XTickLabels(text);
  int x_label_extent = int(std::ceil(font));  // height of the x tick labels
  if (text.vertical_x_labels) {
    x_label_extent = 0;
    for (const auto& l : x_labels) x_label_extent = std::max(x_label_extent, TextWidth(l, font));
  }
  frame->legend_band_top = kPad + (text.title.empty() ? 0 : int(std::ceil(title_font)) + kGap);
  frame->top = frame->legend_band_top + legend_band +
               (text.title.empty() && legend_band == 0 ? int(0.5 * font) : kGap * 2);
  frame->left = kPad + (text.y_label.empty() ? 0 : int(std::ceil(label_font)) + kGap * 2) +
                y_label_width + kGap + kTickLength;
  frame->bottom =
      frame->canvas.height - (kPad + (text.x_label.empty() ? 0 : int(std::ceil(label_font)) + kGap) +
                              x_label_extent + kGap + kTickLength);
  const int last_half =
      x_labels.empty() || text.vertical_x_labels ? 0 : TextWidth(x_labels.back(), font) / 2;
  frame->right = frame->canvas.width - std::max(kPad + s * 4, last_half + kPad / 2);
  SAMP_CHECK(frame->right - frame->left > 20 * s && frame->bottom - frame->top > 20 * s)
      << "plot: image of " << width << "x" << height << " px is too small for its labels";
}

// Draws title, labels, grid, ticks and frame.
void DrawAxes(const AxisText& text, Frame* frame) {
  const int s = kSupersample;
  const double font = frame->font;
  const double label_font = (text.font_px + 1) * s;
  const double title_font = (text.font_px + 4) * s;
  const std::vector<std::string> y_labels = YTickLabels(text);
  const std::vector<std::string> x_labels = XTickLabels(text);
  RgbImage* c = &frame->canvas;
  if (text.grid) {
    for (double t : text.y_ticks) {
      const double y = frame->Py(t);
      DrawLine(c, frame->left, y, frame->right, y, kGridColor, s);
    }
    if (text.x_grid) {
      for (double t : text.x_ticks) {
        const double x = frame->Px(t);
        DrawLine(c, x, frame->top, x, frame->bottom, kGridColor, s);
      }
    }
  }
  for (size_t i = 0; i < text.y_ticks.size(); ++i) {
    const double y = frame->Py(text.y_ticks[i]);
    DrawLine(c, frame->left - kTickLength, y, frame->left, y, kAxisColor, s);
    DrawText(c, y_labels[i], frame->left - kTickLength - kGap, int(std::lround(y)),
             MakeTextStyle(font, HAlign::kRight, VAlign::kMiddle));
  }
  for (size_t i = 0; i < text.x_ticks.size() && i < x_labels.size(); ++i) {
    const double x = frame->Px(text.x_ticks[i]);
    DrawLine(c, x, frame->bottom, x, frame->bottom + kTickLength, kAxisColor, s);
    TextStyle style = MakeTextStyle(font, HAlign::kCenter, VAlign::kTop);
    style.vertical = text.vertical_x_labels;
    DrawText(c, x_labels[i], int(std::lround(x)), frame->bottom + kTickLength + kGap, style);
  }
  // Frame: left and bottom spines darker, top and right lighter.
  DrawLine(c, frame->left, frame->top, frame->right, frame->top, kLightGray, s);
  DrawLine(c, frame->right, frame->top, frame->right, frame->bottom, kLightGray, s);
  DrawLine(c, frame->left, frame->bottom, frame->right, frame->bottom, kAxisColor, s);
  DrawLine(c, frame->left, frame->top, frame->left, frame->bottom, kAxisColor, s);
  if (!text.title.empty()) {
    DrawText(c, text.title, (frame->left + frame->right) / 2, kPad,
             MakeTextStyle(title_font, HAlign::kCenter, VAlign::kTop, /*bold=*/true));
  }
  if (!text.x_label.empty()) {
    DrawText(c, text.x_label, (frame->left + frame->right) / 2, c->height - kPad,
             MakeTextStyle(label_font, HAlign::kCenter, VAlign::kBottom));
  }
  if (!text.y_label.empty()) {
    TextStyle style = MakeTextStyle(label_font, HAlign::kLeft, VAlign::kMiddle);
    style.vertical = true;
    DrawText(c, text.y_label, kPad, (frame->top + frame->bottom) / 2, style);
  }
}

cv::Point ToFixed(double x, double y) {
  constexpr double kLimit = 1e6;  // keep fixed-point coordinates in range
  x = std::clamp(x, -kLimit, kLimit), y = std::clamp(y, -kLimit, kLimit);
  return cv::Point(int(std::lround(x * 16)), int(std::lround(y * 16)));
}

// Draws a polyline into `roi` (already offset), solid or dashed.
void DrawPolyline(cv::Mat* roi, const std::vector<cv::Point2d>& points, Rgb color, int thickness,
                  bool dashed) {
  if (points.size() < 2 || thickness <= 0) return;
  const double dash = 7.0 * kSupersample * std::max(1, thickness / kSupersample);
  const double space = 0.6 * dash;
  double phase = 0.0;  // distance into the current dash+space period
  for (size_t i = 1; i < points.size(); ++i) {
    const cv::Point2d a = points[i - 1], b = points[i];
    if (!dashed) {
      cv::line(*roi, ToFixed(a.x, a.y), ToFixed(b.x, b.y), ToScalar(color), thickness, cv::LINE_AA, 4);
      continue;
    }
    const double length = std::hypot(b.x - a.x, b.y - a.y);
    double t = 0.0;
    while (t < length) {
      const bool on = phase < dash;
      const double run = std::min(length - t, on ? dash - phase : dash + space - phase);
      if (on) {
        const cv::Point2d p = a + (b - a) * (t / length), q = a + (b - a) * ((t + run) / length);
        cv::line(*roi, ToFixed(p.x, p.y), ToFixed(q.x, q.y), ToScalar(color), thickness, cv::LINE_AA, 4);
      }
      t += run;
      phase = std::fmod(phase + run, dash + space);
    }
  }
}

void DrawMarker(cv::Mat* roi, cv::Point2d p, Marker marker, double diameter, Rgb color) {
  if (marker == Marker::kNone || diameter <= 0) return;
  const double r = 0.5 * diameter;
  const cv::Scalar fill = ToScalar(color), edge = ToScalar(kWhite);
  const int edge_width = std::max(1, kSupersample);
  std::vector<cv::Point> polygon;
  switch (marker) {
    case Marker::kCircle:
      cv::circle(*roi, ToFixed(p.x, p.y), int(std::lround(r * 16)), fill, cv::FILLED, cv::LINE_AA, 4);
      cv::circle(*roi, ToFixed(p.x, p.y), int(std::lround(r * 16)), edge, edge_width, cv::LINE_AA, 4);
      return;
    case Marker::kSquare:
      polygon = {ToFixed(p.x - r, p.y - r), ToFixed(p.x + r, p.y - r), ToFixed(p.x + r, p.y + r),
                 ToFixed(p.x - r, p.y + r)};
      break;
    case Marker::kTriangle:
      polygon = {ToFixed(p.x, p.y - 1.15 * r), ToFixed(p.x + 1.1 * r, p.y + 0.75 * r),
                 ToFixed(p.x - 1.1 * r, p.y + 0.75 * r)};
      break;
    case Marker::kDiamond:
      polygon = {ToFixed(p.x, p.y - 1.25 * r), ToFixed(p.x + r, p.y), ToFixed(p.x, p.y + 1.25 * r),
                 ToFixed(p.x - r, p.y)};
      break;
    case Marker::kNone:
      return;
  }
  cv::fillPoly(*roi, std::vector<std::vector<cv::Point>>{polygon}, fill, cv::LINE_AA, 4);
  cv::polylines(*roi, std::vector<std::vector<cv::Point>>{polygon}, true, edge, edge_width,
                cv::LINE_AA, 4);
}

struct LegendEntry {
  std::string label;
  Rgb color;
  double line_width = 2.0;  // 0 = marker only
  bool dashed = false;
  Marker marker = Marker::kNone;
  double marker_size = 7.0;
  bool bar = false;         // a filled swatch instead of a line
};

// Legend geometry in canvas pixels.
struct LegendGeometry {
  int sample = 26 * kSupersample, gap = 7 * kSupersample, row = 0;
  std::vector<int> item_widths;  // swatch + gap + text, per entry
  int box_w = 0, box_h = 0;       // stacked box for corners
};

LegendGeometry MeasureLegend(const std::vector<LegendEntry>& entries, double font) {
  LegendGeometry g;
  g.row = int(std::ceil(font * 1.45));
  int text_width = 0;
  for (const auto& e : entries) {
    const int w = TextWidth(e.label, font);
    text_width = std::max(text_width, w);
    g.item_widths.push_back(g.sample + g.gap + w);
  }
  g.box_w = g.gap + g.sample + g.gap + text_width + g.gap;
  g.box_h = g.gap + g.row * int(entries.size()) + g.gap / 2;
  return g;
}

// Rows of entry indices for a horizontal legend no wider than `width`.
std::vector<std::vector<int>> LegendRows(const LegendGeometry& g, int width) {
  std::vector<std::vector<int>> rows(1);
  int used = 0;
  const int spacing = 3 * g.gap;
  for (int i = 0; i < int(g.item_widths.size()); ++i) {
    const int need = g.item_widths[i] + (rows.back().empty() ? 0 : spacing);
    if (!rows.back().empty() && used + need > width) {
      rows.emplace_back();
      used = 0;
    }
    used += rows.back().empty() ? g.item_widths[i] : need;
    rows.back().push_back(i);
  }
  return rows;
}

int LegendBandHeight(const std::vector<LegendEntry>& entries, const Frame& frame) {
  const LegendGeometry g = MeasureLegend(entries, frame.font);
  return g.row * int(LegendRows(g, frame.right - frame.left).size());
}

cv::Rect CornerBox(LegendPosition p, const LegendGeometry& g, const Frame& frame) {
  const int inset = 8 * kSupersample;
  const bool left = p == LegendPosition::kTopLeft || p == LegendPosition::kBottomLeft;
  const bool top = p == LegendPosition::kTopLeft || p == LegendPosition::kTopRight;
  const int x = left ? frame.left + inset : frame.right - inset - g.box_w;
  const int y = top ? frame.top + inset : frame.bottom - inset - g.box_h;
  return cv::Rect(x, y, g.box_w, g.box_h);
}

// kAuto -> the first corner whose box covers none of the data points
// (`occupied`, data coordinates), else kAbove.
LegendPosition ResolveLegend(const std::vector<LegendEntry>& entries, LegendPosition requested,
                             const std::vector<cv::Point2d>& occupied, const Frame& frame) {
  if (entries.empty()) return LegendPosition::kNone;
  if (requested != LegendPosition::kAuto) return requested;
  const LegendGeometry g = MeasureLegend(entries, frame.font);
  const int pad = 3 * kSupersample;
  for (LegendPosition p : {LegendPosition::kTopRight, LegendPosition::kTopLeft,
                           LegendPosition::kBottomRight, LegendPosition::kBottomLeft}) {
    cv::Rect box = CornerBox(p, g, frame);
    box.x -= pad, box.y -= pad, box.width += 2 * pad, box.height += 2 * pad;
    const bool free = std::none_of(occupied.begin(), occupied.end(), [&](const cv::Point2d& q) {
      return box.contains(cv::Point(int(frame.Px(q.x)), int(frame.Py(q.y))));
    });
    if (free) return p;
  }
  return LegendPosition::kAbove;
}

void DrawSwatch(cv::Mat* mat, const LegendEntry& e, double x0, double cy, double sample, double font) {
  const int s = kSupersample;
  if (e.bar) {
    cv::rectangle(*mat, cv::Point(int(x0 + 4 * s), int(cy - 0.35 * font)),
                  cv::Point(int(x0 + sample - 4 * s), int(cy + 0.35 * font)), ToScalar(e.color),
                  cv::FILLED);
    return;
  }
  const int thickness = int(std::lround(e.line_width * s));
  DrawPolyline(mat, {cv::Point2d(x0, cy), cv::Point2d(x0 + sample, cy)}, e.color, thickness, e.dashed);
  DrawMarker(mat, cv::Point2d(x0 + 0.5 * sample, cy), e.marker, e.marker_size * s, e.color);
}

void DrawLegend(const std::vector<LegendEntry>& entries, LegendPosition position, Frame* frame) {
  if (entries.empty() || position == LegendPosition::kNone || position == LegendPosition::kAuto) {
    return;
  }
  const int s = kSupersample;
  const double font = frame->font;
  const LegendGeometry g = MeasureLegend(entries, font);
  cv::Mat mat = AsMat(&frame->canvas);
  if (position == LegendPosition::kAbove) {
    const auto rows = LegendRows(g, frame->right - frame->left);
    const int spacing = 3 * g.gap;
    for (size_t r = 0; r < rows.size(); ++r) {
      int row_width = 0;
      for (int i : rows[r]) row_width += g.item_widths[i];
      row_width += spacing * (int(rows[r].size()) - 1);
      double x = 0.5 * (frame->left + frame->right - row_width);
      const double cy = frame->legend_band_top + g.row * (r + 0.5);
      for (int i : rows[r]) {
        DrawSwatch(&mat, entries[i], x, cy, g.sample, font);
        DrawText(&frame->canvas, entries[i].label, int(x + g.sample + g.gap), int(std::lround(cy)),
                 MakeTextStyle(font, HAlign::kLeft, VAlign::kMiddle));
        x += g.item_widths[i] + spacing;
      }
    }
    return;
  }
  const cv::Rect box = CornerBox(position, g, *frame);
  // Slightly translucent white box with a light border.
  cv::Mat roi = mat(box & cv::Rect(0, 0, mat.cols, mat.rows));
  cv::Mat white(roi.size(), roi.type(), cv::Scalar(255, 255, 255));
  cv::addWeighted(roi, 0.12, white, 0.88, 0.0, roi);
  cv::rectangle(mat, box, ToScalar(kLightGray), s, cv::LINE_8);
  for (size_t i = 0; i < entries.size(); ++i) {
    const double cy = box.y + g.gap + g.row * (i + 0.5);
    const double x0 = box.x + g.gap;
    DrawSwatch(&mat, entries[i], x0, cy, g.sample, font);
    DrawText(&frame->canvas, entries[i].label, int(x0 + g.sample + g.gap), int(std::lround(cy)),
             MakeTextStyle(font, HAlign::kLeft, VAlign::kMiddle));
  }
}

// Lays out the frame (with a legend band when the legend goes above the plot)
// and draws the axes; returns the legend position to draw at the end.
LegendPosition LayoutWithLegend(const AxisText& text, int width, int height,
                                const std::vector<LegendEntry>& legend, LegendPosition requested,
                                const std::vector<cv::Point2d>& occupied, Frame* frame) {
  Layout(text, width, height, 0, frame);
  const LegendPosition position = ResolveLegend(legend, requested, occupied, *frame);
  if (position == LegendPosition::kAbove) {
    Layout(text, width, height, LegendBandHeight(legend, *frame), frame);
  }
  DrawAxes(text, frame);
  return position;
}

RgbImage Finish(const Frame& frame, int width, int height) {
  return Resize(frame.canvas, width, height);
}

void CheckCommon(int width, int height, int max_ticks, double font_px, const char* what) {
  SAMP_CHECK(width >= 100 && width <= 10000) << what << ".width must be in [100, 10000], got " << width;
  SAMP_CHECK(height >= 80 && height <= 10000) << what << ".height must be in [80, 10000], got " << height;
  SAMP_CHECK(max_ticks >= 2) << what << ".max_ticks must be >= 2, got " << max_ticks;
  SAMP_CHECK(font_px >= 4 && font_px <= 200) << what << ".font_px must be in [4, 200], got " << font_px;
}

}  // namespace

// ---- Line plots ----------------------------------------------------------------

void LinePlotOptions::Check() const {
  CheckCommon(width, height, max_ticks, font_px, "LinePlotOptions");
  for (auto v : {x_min, x_max, y_min, y_max}) {
    SAMP_CHECK(!v || std::isfinite(*v)) << "LinePlotOptions: axis limits must be finite";
  }
  SAMP_CHECK(!(x_min && x_max) || *x_max > *x_min) << "LinePlotOptions.x_max must exceed x_min";
  SAMP_CHECK(!(y_min && y_max) || *y_max > *y_min) << "LinePlotOptions.y_max must exceed y_min";
}

RgbImage DrawLinePlot(const std::vector<PlotSeries>& series, const LinePlotOptions& options) {
  options.Check();
  Range x_range, y_range;
  std::vector<cv::Point2d> occupied;  // data coordinates of points and segment samples
  std::vector<LegendEntry> legend;
  for (size_t i = 0; i < series.size(); ++i) {
    const PlotSeries& s = series[i];
    SAMP_CHECK(s.x.size() == s.y.size()) << "DrawLinePlot: series " << i << " ('" << s.label
                                         << "') has " << s.x.size() << " x but " << s.y.size()
                                         << " y values";
    SAMP_CHECK(s.line_width >= 0 && s.marker_size >= 0)
        << "DrawLinePlot: series " << i << " has a negative line width or marker size";
    SAMP_CHECK(s.point_labels.empty() || s.point_labels.size() == s.x.size())
        << "DrawLinePlot: series " << i << " ('" << s.label << "') has " << s.point_labels.size()
        << " point labels for " << s.x.size() << " points";
    bool previous_finite = false;
    for (size_t j = 0; j < s.x.size(); ++j) {
      const bool finite = std::isfinite(s.x[j]) && std::isfinite(s.y[j]);
      if (finite) {
        x_range.Add(s.x[j]);
        y_range.Add(s.y[j]);
        const cv::Point2d p(s.x[j], s.y[j]);
        if (previous_finite && s.line_width > 0) {
          const cv::Point2d a(s.x[j - 1], s.y[j - 1]);
          for (int k = 1; k < 16; ++k) occupied.push_back(a + (p - a) * (k / 16.0));
        }
        occupied.push_back(p);
      }
      previous_finite = finite;
    }
    if (!s.label.empty()) {
      legend.push_back({s.label, s.color ? *s.color : PaletteColor(int(i)), s.line_width, s.dashed,
                        s.marker, s.marker_size, false});
    }
  }
  Frame frame;
  AxisText text;
  text.title = options.title, text.x_label = options.x_label, text.y_label = options.y_label;
  text.grid = options.grid;
  text.font_px = options.font_px;
  ResolveAxis(x_range, options.x_min, options.x_max, options.max_ticks, "x", &frame.x_lo,
              &frame.x_hi, &text.x_ticks, kDataPadding);
  ResolveAxis(y_range, options.y_min, options.y_max, options.max_ticks, "y", &frame.y_lo,
              &frame.y_hi, &text.y_ticks, kDataPadding);
  // Point labels cover a box above their points: roughly, in data units (the
  // plot's size in pixels is not laid out yet), for the legend's placement.
  const double label_px = std::max(4.0, options.font_px - 3);
  for (const PlotSeries& ps : series) {
    for (size_t j = 0; j < ps.point_labels.size(); ++j) {
      if (ps.point_labels[j].empty() || !std::isfinite(ps.x[j]) || !std::isfinite(ps.y[j])) continue;
      const double up = (0.5 * ps.marker_size + 3 + 0.6 * label_px) / (0.7 * options.height) * (frame.y_hi - frame.y_lo);
      const double half = 0.5 * TextWidth(ps.point_labels[j], label_px) / (0.8 * options.width) *
                          (frame.x_hi - frame.x_lo);
      for (double dx : {-half, 0.0, half}) occupied.push_back(cv::Point2d(ps.x[j] + dx, ps.y[j] + up));
    }
  }
  const LegendPosition legend_position = LayoutWithLegend(
      text, options.width, options.height, legend, options.legend, occupied, &frame);

  const int s = kSupersample;
  cv::Mat mat = AsMat(&frame.canvas);
  // Clip the data to the plot rectangle (plus a pixel for the line at the border).
  const cv::Rect clip(frame.left, frame.top - s, frame.right - frame.left + 1 + s,
                      frame.bottom - frame.top + 1 + s);
  cv::Mat roi = mat(clip);
  const cv::Point2d offset(clip.x, clip.y);
  for (size_t i = 0; i < series.size(); ++i) {
    const PlotSeries& ps = series[i];
    const Rgb color = ps.color ? *ps.color : PaletteColor(int(i));
    const int thickness = int(std::lround(ps.line_width * s));
    std::vector<cv::Point2d> run, all;
    auto flush = [&] {
      DrawPolyline(&roi, run, color, thickness, ps.dashed);
      run.clear();
    };
    for (size_t j = 0; j < ps.x.size(); ++j) {
      if (!std::isfinite(ps.x[j]) || !std::isfinite(ps.y[j])) {
        flush();
        continue;
      }
      const cv::Point2d p = cv::Point2d(frame.Px(ps.x[j]), frame.Py(ps.y[j])) - offset;
      run.push_back(p);
      all.push_back(p);
    }
    flush();
    for (const auto& p : all) DrawMarker(&roi, p, ps.marker, ps.marker_size * s, color);
  }
  // Point labels on the whole canvas (not clipped to the plot), above their points.
  for (size_t i = 0; i < series.size(); ++i) {
    const PlotSeries& ps = series[i];
    const Rgb color = ps.color ? *ps.color : PaletteColor(int(i));
    for (size_t j = 0; j < ps.point_labels.size(); ++j) {
      if (ps.point_labels[j].empty() || !std::isfinite(ps.x[j]) || !std::isfinite(ps.y[j])) continue;
      const double above = 0.5 * ps.marker_size * s + 3 * s;
      DrawText(&frame.canvas, ps.point_labels[j], int(std::lround(frame.Px(ps.x[j]))),
               int(std::lround(frame.Py(ps.y[j]) - above)),
               MakeTextStyle(label_px * s, HAlign::kCenter, VAlign::kBottom, false, color));
    }
  }
  DrawLegend(legend, legend_position, &frame);
  return Finish(frame, options.width, options.height);
}

// ---- Bar plots -----------------------------------------------------------------

void BarPlotOptions::Check() const {
  CheckCommon(width, height, max_ticks, font_px, "BarPlotOptions");
  for (auto v : {y_min, y_max}) {
    SAMP_CHECK(!v || std::isfinite(*v)) << "BarPlotOptions: axis limits must be finite";
  }
  SAMP_CHECK(!(y_min && y_max) || *y_max > *y_min) << "BarPlotOptions.y_max must exceed y_min";
  SAMP_CHECK(value_precision >= 0 && value_precision <= 10)
      << "BarPlotOptions.value_precision must be in [0, 10], got " << value_precision;
}

RgbImage DrawBarPlot(const std::vector<std::string>& categories,
                     const std::vector<BarSeries>& series, const BarPlotOptions& options) {
  options.Check();
  SAMP_CHECK(!categories.empty()) << "DrawBarPlot: no categories";
  SAMP_CHECK(!series.empty()) << "DrawBarPlot: no series";
  const int n = int(categories.size());
  const int num_series = int(series.size());
  constexpr double kGroupWidth = 0.78;  // of a category's slot
  const double bar = kGroupWidth / num_series;
  auto bar_left = [&](int category, int s) { return category - 0.5 * kGroupWidth + s * bar; };

  Range y_range;
  y_range.Add(0.0);
  std::vector<cv::Point2d> occupied;  // data coordinates covered by bars
  for (int si = 0; si < num_series; ++si) {
    const BarSeries& b = series[si];
    SAMP_CHECK(b.values.size() == categories.size())
        << "DrawBarPlot: series " << si << " ('" << b.label << "') has " << b.values.size()
        << " values for " << categories.size() << " categories";
    SAMP_CHECK(b.errors.empty() || b.errors.size() == b.values.size())
        << "DrawBarPlot: series " << si << " has " << b.errors.size() << " errors for "
        << b.values.size() << " values";
    for (int c = 0; c < n; ++c) {
      const double v = b.values[c];
      if (!std::isfinite(v)) continue;
      const double e = b.errors.empty() || !std::isfinite(b.errors[c]) ? 0.0 : std::abs(b.errors[c]);
      y_range.Add(v + e);
      y_range.Add(v - e);
      for (int fx = 0; fx <= 4; ++fx) {
        for (int fy = 0; fy <= 8; ++fy) {
          occupied.emplace_back(bar_left(c, si) + bar * fx / 4.0,
                                (v >= 0 ? v + e : v - e) * fy / 8.0);
        }
      }
    }
  }
  for (double r : options.reference_lines) y_range.Add(r);
  if (options.symmetric) {
    const double m = std::max(std::abs(y_range.lo), std::abs(y_range.hi));
    y_range.lo = -m, y_range.hi = m;
  }
  Frame frame;
  AxisText text;
  text.title = options.title, text.x_label = options.x_label, text.y_label = options.y_label;
  text.grid = options.grid;
  text.x_grid = false;
  text.font_px = options.font_px;
  ResolveAxis(y_range, options.y_min, options.y_max, options.max_ticks, "y", &frame.y_lo,
              &frame.y_hi, &text.y_ticks);
  if (options.symmetric && !options.y_min && !options.y_max) {  // keep 0 in the middle
    const double m = std::max(std::abs(frame.y_lo), std::abs(frame.y_hi));
    frame.y_lo = -m, frame.y_hi = m;
    text.y_ticks = NiceTicks(-m, m, options.max_ticks);
  }
  frame.x_lo = -0.5, frame.x_hi = n - 0.5;
  for (int i = 0; i < n; ++i) text.x_ticks.push_back(i);
  text.x_tick_labels = categories;
  // Category labels turn vertical when they do not fit their slot.
  {
    const double slot = double(options.width) * 0.8 / n;
    int widest = 0;
    for (const auto& c : categories) widest = std::max(widest, TextWidth(c, options.font_px));
    text.vertical_x_labels = widest > 0.9 * slot;
  }
  std::vector<LegendEntry> legend;
  int labelled = 0;
  for (const auto& b : series) labelled += b.label.empty() ? 0 : 1;
  if (labelled > 1) {
    for (int si = 0; si < num_series; ++si) {
      if (series[si].label.empty()) continue;
      LegendEntry e;
      e.label = series[si].label;
      e.color = series[si].color ? *series[si].color : PaletteColor(si);
      e.bar = true;
      legend.push_back(e);
    }
  }
  const LegendPosition legend_position = LayoutWithLegend(
      text, options.width, options.height, legend, options.legend, occupied, &frame);

  const int s = kSupersample;
  cv::Mat mat = AsMat(&frame.canvas);
  const double y0 = frame.Py(std::clamp(0.0, frame.y_lo, frame.y_hi));
  const double bar_px = bar * (frame.right - frame.left) / n;
  for (int si = 0; si < num_series; ++si) {
    const BarSeries& b = series[si];
    const Rgb color = b.color ? *b.color : PaletteColor(si);
    for (int c = 0; c < n; ++c) {
      const double v = b.values[c];
      if (!std::isfinite(v)) continue;
      const double x_left = frame.Px(bar_left(c, si));
      const double x_right = x_left + bar_px - (num_series > 1 ? 1.0 * s : 0.0);
      const double yv = std::clamp(frame.Py(v), double(frame.top), double(frame.bottom));
      cv::rectangle(mat, cv::Point(int(std::lround(x_left)), int(std::lround(std::min(y0, yv)))),
                    cv::Point(int(std::lround(x_right)) - 1, int(std::lround(std::max(y0, yv)))),
                    ToScalar(color), cv::FILLED, cv::LINE_8);
      const double cx = 0.5 * (x_left + x_right);
      double label_y = yv;
      if (!b.errors.empty() && std::isfinite(b.errors[c]) && b.errors[c] != 0.0) {
        const double e = std::abs(b.errors[c]);
        const double ya = frame.Py(v - e), yb = frame.Py(v + e);
        const double cap = std::min(0.25 * bar_px, 6.0 * s);
        DrawLine(&frame.canvas, cx, ya, cx, yb, kDarkGray, s);
        DrawLine(&frame.canvas, cx - cap, ya, cx + cap, ya, kDarkGray, s);
        DrawLine(&frame.canvas, cx - cap, yb, cx + cap, yb, kDarkGray, s);
        label_y = v >= 0 ? yb : ya;
      }
      if (options.show_values) {
        char buffer[64];
        std::snprintf(buffer, sizeof(buffer), "%.*f", options.value_precision, v);
        const double size = std::max(8.0 * s, 0.8 * frame.font);
        DrawText(&frame.canvas, buffer, int(std::lround(cx)),
                 int(std::lround(v >= 0 ? label_y - 3 * s : label_y + 3 * s)),
                 MakeTextStyle(size, HAlign::kCenter, v >= 0 ? VAlign::kBottom : VAlign::kTop, false,
                       kDarkGray));
      }
    }
  }
  // Zero line and reference lines on top of the bars.
  if (frame.y_lo < 0 && frame.y_hi > 0) {
    DrawLine(&frame.canvas, frame.left, y0, frame.right, y0, kAxisColor, s);
  }
  for (double r : options.reference_lines) {
    if (r < frame.y_lo || r > frame.y_hi) continue;
    std::vector<cv::Point2d> line = {cv::Point2d(frame.left, frame.Py(r)),
                                     cv::Point2d(frame.right, frame.Py(r))};
    DrawPolyline(&mat, line, kGray, s, /*dashed=*/true);
  }
  DrawLegend(legend, legend_position, &frame);
  return Finish(frame, options.width, options.height);
}

}  // namespace samp
