// Small, good-looking static plots drawn with OpenCV into an RgbImage (no
// display): line/scatter plots with several series, and (grouped) bar plots.
// Axes get "nice" ticks (1, 2, 5 x 10^k) with labels, a light grid, a title,
// axis labels and a legend. Everything is drawn at 2x and downsampled, so
// lines and markers are smooth. Save with WritePng(path, image) (image.h).
//
//   samp::PlotSeries f1{"F1", taus, f1s};
//   samp::LinePlotOptions options;
//   options.title = "Reconstruction quality";
//   options.x_label = "tau [m]";
//   options.y_min = 0, options.y_max = 1;
//   samp::WritePng("f1.png", samp::DrawLinePlot({f1, accuracy, completeness}, options));
//
// Pure functions of their arguments; thread-safe.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "libsamp/viz/image.h"

namespace samp {

enum class Marker { kNone, kCircle, kSquare, kTriangle, kDiamond };
// Legend placement. kAuto: the corner of the plot covering no data (the
// emptiest one, tried in the order top-right, top-left, bottom-right,
// bottom-left), else a row above the plot (kAbove).
enum class LegendPosition { kAuto, kTopLeft, kTopRight, kBottomLeft, kBottomRight, kAbove, kNone };

// One series of a line plot. Points with a non-finite x or y break the line.
struct PlotSeries {
  std::string label;             // legend entry; "" = not listed in the legend
  std::vector<double> x, y;      // same length
  std::optional<Rgb> color;      // default: PaletteColor(series index)
  double line_width = 2.0;       // pixels; 0 = markers only (scatter plot)
  bool dashed = false;
  Marker marker = Marker::kNone;
  double marker_size = 7.0;      // marker diameter, pixels
  // Text above each point (e.g. its sample count), in the series' colour at
  // the tick labels' size less 3 px; empty, or one per point ("" = none).
  std::vector<std::string> point_labels;
};

struct LinePlotOptions {
  int width = 800;               // image size, pixels
  int height = 500;
  std::string title, x_label, y_label;
  // Axis ranges; unset = the data range, extended to the enclosing ticks.
  std::optional<double> x_min, x_max, y_min, y_max;
  int max_ticks = 8;             // upper bound on ticks per axis (>= 2)
  bool grid = true;              // light grid lines at the ticks
  LegendPosition legend = LegendPosition::kAuto;
  double font_px = 15.0;         // tick labels; axis labels +1, title +4 (bold)

  // Throws samp::Error naming the field when an option is invalid.
  void Check() const;
};

// Throws samp::Error on invalid options, series with x.size() != y.size() (or
// point labels not one per point), or when no series has a finite point and
// the ranges are not all given.
RgbImage DrawLinePlot(const std::vector<PlotSeries>& series, const LinePlotOptions& options);

// One group member of a bar plot: a value per category.
struct BarSeries {
  std::string label;             // legend entry; "" = not listed
  std::vector<double> values;    // one per category (non-finite = no bar)
  std::optional<Rgb> color;      // default: PaletteColor(series index)
  // Optional symmetric error bars (same length as values, or empty).
  std::vector<double> errors;
};

struct BarPlotOptions {
  int width = 600;               // image size, pixels
  int height = 400;
  std::string title, x_label, y_label;
  std::optional<double> y_min, y_max;  // unset: data range including 0, to the ticks
  bool symmetric = false;        // y range symmetric around 0 (e.g. shape codes)
  // Horizontal reference lines drawn dashed (e.g. +-1 for a code in sigmas).
  std::vector<double> reference_lines;
  bool show_values = false;      // print each bar's value above/below it
  int value_precision = 2;       // digits after the point for show_values
  int max_ticks = 8;
  bool grid = true;
  LegendPosition legend = LegendPosition::kAuto;  // only drawn with >1 labelled series
  double font_px = 15.0;

  void Check() const;
};

// Grouped bars: one group per category, one bar per series in each group.
// Throws samp::Error on invalid options or when a series' size differs from
// categories.size().
RgbImage DrawBarPlot(const std::vector<std::string>& categories,
                     const std::vector<BarSeries>& series, const BarPlotOptions& options);

// "Nice" tick positions covering [lo, hi] with at most max_ticks ticks
// (steps 1, 2, 2.5 or 5 x 10^k); exposed for tests and custom figures.
std::vector<double> NiceTicks(double lo, double hi, int max_ticks);
// Formats a tick value with as many decimals as `step` needs ("0.25", "1e-05", "-3").
std::string FormatTick(double value, double step);

}  // namespace samp
