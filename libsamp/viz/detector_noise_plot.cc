#include "libsamp/viz/detector_noise_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "libsamp/core/error.h"
#include "libsamp/viz/plot.h"

namespace samp {
namespace {

// Text is ASCII: OpenCV's Hershey font (no TrueType font installed) has no
// Greek letters or degree signs.
std::string Format(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

// Where a bin's sigmas are drawn: the mean distance of its detections, else
// (a file without it) its middle; the open last bin (max_distance 1e3) then
// half a previous bin's width (or 5 m) beyond its start.
std::vector<double> BinDistances(const std::vector<DistanceBin>& bins) {
  constexpr double kOpen = 999.0;
  std::vector<double> x;
  for (size_t i = 0; i < bins.size(); ++i) {
    const DistanceBin& b = bins[i];
    if (b.mean_distance > 0) {
      x.push_back(b.mean_distance);
    } else if (b.max_distance < kOpen) {
      x.push_back(0.5 * (b.min_distance + b.max_distance));
    } else {
      const double width = i > 0 && bins[i - 1].max_distance < kOpen ? bins[i - 1].max_distance - bins[i - 1].min_distance
                                                                      : 10.0;
      x.push_back(b.min_distance + 0.5 * width);
    }
  }
  return x;
}

// One position cue: its name, the fitted a + b d and each bin's sigma and centre.
struct Cue {
  std::string title;
  double a = 0.0, b = 0.0;
  double DistanceBin::*sigma;
  double DistanceBin::*center;
  bool with_model_bias = false;  // along the ray: the model's along_bias
};

RgbImage DrawCuePanel(const DetectorNoiseModel& model, const Cue& cue, const DetectorNoisePlotOptions& options) {
  const std::vector<double> x = BinDistances(model.bins);
  // The closed bins' edges, and room right of the last bin for its count.
  double x_max = 0.0;
  for (size_t i = 0; i < model.bins.size(); ++i) {
    x_max = std::max(x_max, x[i] / 0.9);
    if (model.bins[i].max_distance < 999.0) x_max = std::max(x_max, model.bins[i].max_distance);
  }
  if (x_max <= 0) x_max = 60.0;  // no bins (a model of defaults): the fit over 0-60 m

  std::vector<PlotSeries> series;
  PlotSeries fit;
  fit.label = "fit: sigma(d) = " + Format("%.3g", cue.a) + " + " + Format("%.3g", cue.b) + " d";
  fit.x = {0.0, x_max};
  fit.y = {cue.a, cue.a + cue.b * x_max};
  fit.color = PaletteColor(0);
  series.push_back(fit);

  PlotSeries measured;
  measured.label = "sigma per bin (n = detections)";
  measured.line_width = 0;
  measured.marker = Marker::kCircle;
  measured.marker_size = 9;
  measured.color = PaletteColor(1);
  double y_max = std::max(fit.y[0], fit.y[1]), y_min = 0.0;
  for (size_t i = 0; i < model.bins.size(); ++i) {
    const DistanceBin& b = model.bins[i];
    measured.x.push_back(x[i]);
    measured.y.push_back(b.*cue.sigma);
    measured.point_labels.push_back("n=" + std::to_string(b.count));
    y_max = std::max(y_max, b.*cue.sigma);
  }
  if (!measured.x.empty()) series.push_back(measured);

  if (model.biases_estimated && !model.bins.empty()) {
    PlotSeries centre;
    centre.label = "centre per bin";
    centre.line_width = 0;
    centre.marker = Marker::kDiamond;
    centre.marker_size = 9;
    centre.color = PaletteColor(2);
    for (size_t i = 0; i < model.bins.size(); ++i) {
      centre.x.push_back(x[i]);
      centre.y.push_back(model.bins[i].*cue.center);
      y_max = std::max(y_max, model.bins[i].*cue.center);
      y_min = std::min(y_min, model.bins[i].*cue.center);
    }
    series.push_back(centre);
    if (cue.with_model_bias) {
      PlotSeries bias;
      bias.label = "along_bias " + Format("%+.3f", model.along_bias) + " m";
      bias.x = {0.0, x_max};
      bias.y = {model.along_bias, model.along_bias};
      bias.dashed = true;
      bias.line_width = 1.5;
      bias.color = PaletteColor(2);
      series.push_back(bias);
      y_max = std::max(y_max, model.along_bias);
      y_min = std::min(y_min, model.along_bias);
    }
  }
  LinePlotOptions plot;
  plot.width = options.panel_width;
  plot.height = options.panel_height;
  plot.font_px = options.font_px;
  plot.title = cue.title;
  plot.x_label = "horizontal distance (m)";
  plot.y_label = "error (m)";
  plot.x_min = 0.0;
  plot.x_max = x_max;
  // Room above the highest marker for its count and below 0 for negative centres.
  const double span = std::max(y_max - y_min, 1e-3);
  plot.y_min = y_min < 0 ? y_min - 0.1 * span : 0.0;
  plot.y_max = y_max + 0.25 * span;
  plot.legend = LegendPosition::kAuto;
  return DrawLinePlot(series, plot);
}

RgbImage DrawSizePanel(const DetectorNoiseModel& model, const DetectorNoisePlotOptions& options) {
  BarSeries sigma;
  sigma.label = "sigma";
  sigma.values = {model.size_sigma[0], model.size_sigma[1], model.size_sigma[2]};
  sigma.color = PaletteColor(1);
  std::vector<BarSeries> series = {sigma};
  if (model.biases_estimated || model.box_convention_estimated) {
    BarSeries bias;
    bias.label = model.box_convention_estimated ? "bias (box - shape)" : "bias (detected - true)";
    bias.values = {model.size_bias[0], model.size_bias[1], model.size_bias[2]};
    bias.color = PaletteColor(2);
    series.push_back(bias);
  }
  BarPlotOptions plot;
  plot.width = options.panel_width;
  plot.height = options.panel_height;
  plot.font_px = options.font_px;
  plot.title = "Box size";
  plot.y_label = "error (m)";
  plot.show_values = true;
  plot.legend = LegendPosition::kAbove;
  return DrawBarPlot({"height", "width", "length"}, series, plot);
}

}  // namespace

void DetectorNoisePlotOptions::Check() const {
  SAMP_CHECK(panel_width >= 200 && panel_width <= 5000)
      << "DetectorNoisePlotOptions.panel_width must be in [200, 5000], got " << panel_width;
  SAMP_CHECK(panel_height >= 150 && panel_height <= 5000)
      << "DetectorNoisePlotOptions.panel_height must be in [150, 5000], got " << panel_height;
  SAMP_CHECK(font_px >= 6 && font_px <= 100) << "DetectorNoisePlotOptions.font_px must be in [6, 100], got " << font_px;
  SAMP_CHECK(header_height >= 2 * font_px)
      << "DetectorNoisePlotOptions.header_height must be >= 2 font_px (the title), got " << header_height;
  SAMP_CHECK(footer_height >= 3 * font_px)
      << "DetectorNoisePlotOptions.footer_height must be >= 3 font_px (two lines of text), got " << footer_height;
}

RgbImage DrawDetectorNoisePlot(const DetectorNoiseModel& model, const DetectorNoisePlotOptions& options) {
  options.Check();
  RgbImage figure(options.Width(), options.Height(), kWhite);
  const Cue cues[3] = {
      {"Along the viewing ray", model.along_sigma_a, model.along_sigma_b, &DistanceBin::along_sigma,
       &DistanceBin::along_bias, true},
      {"Across the ray", model.across_sigma_a, model.across_sigma_b, &DistanceBin::across_sigma,
       &DistanceBin::across_bias, false},
      {"Vertical (camera y)", model.vertical_sigma_a, model.vertical_sigma_b, &DistanceBin::vertical_sigma,
       &DistanceBin::vertical_bias, false}};
  const int top = options.header_height;
  Paste(DrawCuePanel(model, cues[0], options), 0, top, &figure);
  Paste(DrawCuePanel(model, cues[1], options), options.panel_width, top, &figure);
  Paste(DrawCuePanel(model, cues[2], options), 0, top + options.panel_height, &figure);
  Paste(DrawSizePanel(model, options), options.panel_width, top + options.panel_height, &figure);

  const std::string title = options.title.empty() ? "Detector noise model (" + model.source + ")" : options.title;
  DrawText(&figure, title, figure.width / 2, options.header_height / 2,
           MakeTextStyle(options.font_px + 6, HAlign::kCenter, VAlign::kMiddle, /*bold=*/true));
  // Two footer lines, each shrunk to the figure's width when it is too long.
  const std::string rates = "yaw sigma " + Format("%.2f", model.yaw_sigma_deg) + " deg; flips " +
                            Format("%.1f", 100 * model.flip_rate) + " %; misses " +
                            Format("%.1f", 100 * model.miss_rate) + " %; " +
                            Format("%.3g", model.false_positives_per_frame) + " false positives per frame";
  std::string counts = std::to_string(model.num_position_samples) + " detections (position), " +
                       std::to_string(model.num_size_samples) + " (size), " + std::to_string(model.num_yaw_samples) +
                       " (yaw); " + std::to_string(model.num_tracks) + " tracks, " +
                       std::to_string(model.num_frames) + " frames";
  if (!model.notes.empty()) counts += "; " + std::to_string(model.notes.size()) + " note(s) in the JSON";
  const int footer_top = options.header_height + 2 * options.panel_height;
  const double line = options.footer_height / 2.0;
  for (int i = 0; i < 2; ++i) {
    const std::string& text = i == 0 ? rates : counts;
    TextStyle style = MakeTextStyle(options.font_px, HAlign::kCenter, VAlign::kMiddle);
    int width = 0;
    MeasureText(text, style, &width, nullptr);
    if (width > figure.width - 16) style.size_px *= double(figure.width - 16) / width;
    DrawText(&figure, text, figure.width / 2, int(std::lround(footer_top + line * (i + 0.5))), style);
  }
  return figure;
}

void WriteDetectorNoisePlot(const std::string& path, const DetectorNoiseModel& model,
                            const DetectorNoisePlotOptions& options) {
  WritePng(path, DrawDetectorNoisePlot(model, options));
}

}  // namespace samp
