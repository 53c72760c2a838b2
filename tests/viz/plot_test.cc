#include "libsamp/viz/plot.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>

#include "libsamp/core/error.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

// Pictures go to a temporary folder, removed afterwards unless
// SAMP_KEEP_TEST_OUTPUT names a folder to keep them in (for looking at them).
fs::path OutputDir() {
  if (const char* keep = std::getenv("SAMP_KEEP_TEST_OUTPUT")) return fs::path(keep) / "plot";
  return fs::temp_directory_path() / ("samp_viz_plot_" + std::to_string(::getpid()));
}

TEST(Plot, NiceTicks) {
  EXPECT_EQ(NiceTicks(0.0, 1.0, 6), (std::vector<double>{0, 0.2, 0.4, 0.6, 0.8, 1.0}));
  const auto ticks = NiceTicks(0.13, 9.7, 8);
  EXPECT_LE(ticks.size(), 8u);
  EXPECT_LE(ticks.front(), 0.13);
  EXPECT_GE(ticks.back(), 9.7);
  EXPECT_EQ(NiceTicks(-2.2, 2.2, 5), (std::vector<double>{-4, -2, 0, 2, 4}));
  EXPECT_THROW(NiceTicks(1.0, 1.0, 5), Error);
  EXPECT_EQ(FormatTick(0.25, 0.25), "0.25");
  EXPECT_EQ(FormatTick(-3.0, 1.0), "-3");
  EXPECT_EQ(FormatTick(-0.0, 0.5), "0.0");
  EXPECT_EQ(FormatTick(2.0, 0.5), "2.0");
}

TEST(Plot, LinePlotHasSizeAndContent) {
  std::vector<PlotSeries> series(3);
  const char* names[] = {"F1", "accuracy", "completeness"};
  for (int s = 0; s < 3; ++s) {
    series[s].label = names[s];
    series[s].marker = Marker(1 + s);
    for (int i = 0; i <= 20; ++i) {
      const double tau = 0.01 * i;
      series[s].x.push_back(tau);
      series[s].y.push_back(1.0 - std::exp(-tau * (10 + 8 * s)));
    }
  }
  series[2].dashed = true;
  series[1].y[7] = std::numeric_limits<double>::quiet_NaN();  // a gap
  LinePlotOptions options;
  options.title = "Reconstruction quality vs tau";
  options.x_label = "tau [m]";
  options.y_label = "score";
  options.y_min = 0.0;
  options.y_max = 1.0;
  const RgbImage image = DrawLinePlot(series, options);
  EXPECT_EQ(image.width, 800);
  EXPECT_EQ(image.height, 500);
  EXPECT_GT(PixelVariance(image), 100.0);
  // Series colours are present.
  int palette_pixels = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) palette_pixels += image.At(x, y) == PaletteColor(0);
  EXPECT_GT(palette_pixels, 100);
  const fs::path dir = OutputDir();
  WritePng((dir / "line.png").string(), image);
  EXPECT_TRUE(fs::exists(dir / "line.png"));

  // Scatter without lines, automatic ranges, negative values.
  PlotSeries scatter{"pose error", {5, 10, 15, 20, 30, 45}, {0.1, 0.15, -0.05, 0.4, 0.5, 1.2}};
  scatter.line_width = 0;
  scatter.marker = Marker::kCircle;
  scatter.marker_size = 9;
  LinePlotOptions scatter_options;
  scatter_options.width = 500;
  scatter_options.height = 320;
  scatter_options.x_label = "distance [m]";
  scatter_options.y_label = "translation error [m]";
  const RgbImage scatter_image = DrawLinePlot({scatter}, scatter_options);
  EXPECT_EQ(scatter_image.width, 500);
  EXPECT_GT(PixelVariance(scatter_image), 50.0);
  WritePng((dir / "scatter.png").string(), scatter_image);
  if (!std::getenv("SAMP_KEEP_TEST_OUTPUT")) fs::remove_all(dir);
}

TEST(Plot, BarPlot) {
  BarSeries code{"code", {1.2, -0.4, 0.8, -2.1, 0.05}};
  BarPlotOptions options;
  options.title = "shape code z / sigma";
  options.symmetric = true;
  options.reference_lines = {-1.0, 1.0};
  options.show_values = true;
  const RgbImage image = DrawBarPlot({"z1", "z2", "z3", "z4", "z5"}, {code}, options);
  EXPECT_EQ(image.width, 600);
  EXPECT_EQ(image.height, 400);
  EXPECT_GT(PixelVariance(image), 100.0);

  BarSeries a{"train", {0.1, 0.2, 0.15}, std::nullopt, {0.01, 0.03, 0.02}};
  BarSeries b{"held out", {0.2, 0.35, 0.3}, std::nullopt, {0.02, 0.05, 0.04}};
  BarPlotOptions grouped;
  grouped.y_label = "RMS SDF error [m]";
  const RgbImage grouped_image =
      DrawBarPlot({"a rather long category", "another long one", "third category"}, {a, b}, grouped);
  EXPECT_GT(PixelVariance(grouped_image), 50.0);
  const fs::path dir = OutputDir();
  WritePng((dir / "bars.png").string(), image);
  WritePng((dir / "bars_grouped.png").string(), grouped_image);
  if (!std::getenv("SAMP_KEEP_TEST_OUTPUT")) fs::remove_all(dir);

  EXPECT_THROW(DrawBarPlot({"a"}, {code}, options), Error);
  BarPlotOptions bad;
  bad.width = 10;
  EXPECT_THROW(bad.Check(), Error);
}

// Point labels: text above each point in the series' colour; one per point.
TEST(Plot, PointLabels) {
  PlotSeries counts{"sigma", {15, 25, 35, 50}, {0.5, 0.7, 0.9, 1.2}};
  counts.line_width = 0;
  counts.marker = Marker::kCircle;
  LinePlotOptions options;
  options.y_min = 0, options.y_max = 1.6;
  options.legend = LegendPosition::kNone;
  const RgbImage plain = DrawLinePlot({counts}, options);
  counts.point_labels = {"n=196", "n=381", "", "n=1123"};
  const RgbImage labelled = DrawLinePlot({counts}, options);
  // Text pixels in the series' colour (anti-aliased: not only the exact colour) above the points.
  int changed = 0;
  for (int y = 0; y < plain.height; ++y)
    for (int x = 0; x < plain.width; ++x) changed += plain.At(x, y) != labelled.At(x, y);
  EXPECT_GT(changed, 100);
  counts.point_labels = {"n=1"};
  EXPECT_THROW(DrawLinePlot({counts}, options), Error);
}

TEST(Plot, BadInput) {
  PlotSeries mismatched{"m", {1, 2}, {1}};
  EXPECT_THROW(DrawLinePlot({mismatched}, LinePlotOptions()), Error);
  PlotSeries empty{"e", {}, {}};
  EXPECT_THROW(DrawLinePlot({empty}, LinePlotOptions()), Error);
  LinePlotOptions ranged;
  ranged.x_min = 0, ranged.x_max = 1, ranged.y_min = 0, ranged.y_max = 1;
  EXPECT_NO_THROW(DrawLinePlot({empty}, ranged));
  LinePlotOptions inverted;
  inverted.y_min = 1, inverted.y_max = 0;
  EXPECT_THROW(inverted.Check(), Error);
}

}  // namespace
}  // namespace samp
