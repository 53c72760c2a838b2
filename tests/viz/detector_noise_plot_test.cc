// The picture of a detector noise model (viz/detector_noise_plot.h): its
// size, its content (every panel's series drawn, the bins' counts printed),
// models without bins or without the bins' mean distances, and bad options.
#include "libsamp/viz/detector_noise_plot.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>

#include "libsamp/core/error.h"
#include "libsamp/viz/plot.h"
#include "tests/testing/expect_error.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

fs::path OutputDir() {
  if (const char* keep = std::getenv("SAMP_KEEP_TEST_OUTPUT")) return fs::path(keep) / "detector_noise_plot";
  return fs::temp_directory_path() / ("samp_viz_detector_noise_plot_" + std::to_string(::getpid()));
}

// A ground-truth model: sigmas a + b d, five bins (the last open).
DetectorNoiseModel GroundTruthModel() {
  DetectorNoiseModel m;
  m.source = "ground truth";
  m.along_sigma_a = 0.2, m.along_sigma_b = 0.02;
  m.across_sigma_a = 0.08, m.across_sigma_b = 0.004;
  m.vertical_sigma_a = 0.15, m.vertical_sigma_b = 0.0;
  m.along_bias = 0.18;
  m.size_sigma[0] = 0.25, m.size_sigma[1] = 0.4, m.size_sigma[2] = 0.9;
  m.size_bias[0] = 0.1, m.size_bias[1] = -0.25, m.size_bias[2] = 0.3;
  m.biases_estimated = true;
  m.num_position_samples = m.num_size_samples = m.num_yaw_samples = 2684;
  const double edges[6] = {10, 20, 30, 40, 60, 1e3};
  const int counts[5] = {196, 381, 554, 1123, 430};
  const double means[5] = {15.8, 25.4, 35.2, 49.1, 67.3};
  for (int i = 0; i < 5; ++i) {
    DistanceBin b;
    b.min_distance = edges[i], b.max_distance = edges[i + 1], b.count = counts[i], b.mean_distance = means[i];
    b.along_sigma = m.along_sigma_a + m.along_sigma_b * means[i] + 0.03 * (i % 2 ? 1 : -1);
    b.across_sigma = m.across_sigma_a + m.across_sigma_b * means[i];
    b.vertical_sigma = 0.15;
    b.along_bias = 0.18 + 0.02 * (i - 2), b.across_bias = -0.01, b.vertical_bias = 0.005;
    m.bins.push_back(b);
  }
  return m;
}

// Pixels of exactly `color`, in the whole image or in the along-ray panel (top left).
int CountColor(const RgbImage& image, Rgb color, const DetectorNoisePlotOptions* along_panel = nullptr) {
  const int x1 = along_panel ? along_panel->panel_width : image.width;
  const int y0 = along_panel ? along_panel->header_height : 0;
  const int y1 = along_panel ? y0 + along_panel->panel_height : image.height;
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = 0; x < x1; ++x) n += image.At(x, y) == color;
  return n;
}

TEST(DetectorNoisePlot, FourPanelsWithTheBinsAndTheFit) {
  const DetectorNoiseModel m = GroundTruthModel();
  const DetectorNoisePlotOptions options;
  const RgbImage image = DrawDetectorNoisePlot(m, options);
  EXPECT_EQ(image.width, options.Width());
  EXPECT_EQ(image.height, options.Height());
  EXPECT_EQ(options.Width(), 1280);
  EXPECT_EQ(options.Height(), 980);
  EXPECT_GT(PixelVariance(image), 200.0);
  // The fit lines, the measured sigmas and the centres (bias) in their colours.
  for (int series = 0; series < 3; ++series) EXPECT_GT(CountColor(image, PaletteColor(series)), 200) << series;
  // Without biases (self-calibration) the centres are not drawn, and without
  // bins only the fits.
  DetectorNoiseModel self = m;
  self.biases_estimated = false;
  self.source = "self-calibration";
  const RgbImage no_bias = DrawDetectorNoisePlot(self, options);
  EXPECT_LT(CountColor(no_bias, PaletteColor(2)), CountColor(image, PaletteColor(2)) / 4);
  DetectorNoiseModel defaults;
  const RgbImage no_bins = DrawDetectorNoisePlot(defaults, options);
  EXPECT_EQ(no_bins.width, options.Width());
  EXPECT_EQ(CountColor(no_bins, PaletteColor(1), &options), 0);
  EXPECT_GT(CountColor(image, PaletteColor(1), &options), 100);
  // A file written without the bins' mean distances: the bins' middles.
  DetectorNoiseModel old = m;
  for (DistanceBin& b : old.bins) b.mean_distance = 0.0;
  EXPECT_GT(PixelVariance(DrawDetectorNoisePlot(old, options)), 200.0);
  // Smaller panels, another title; the file.
  DetectorNoisePlotOptions small;
  small.panel_width = 420, small.panel_height = 300, small.title = "a detector";
  const fs::path dir = OutputDir();
  const std::string path = (dir / "model.png").string();
  WriteDetectorNoisePlot(path, m, small);
  const RgbImage back = ReadPng(path);
  EXPECT_EQ(back.width, 840);
  EXPECT_EQ(back.height, small.header_height + 600 + small.footer_height);
  WritePng((dir / "model_default.png").string(), image);
  if (!std::getenv("SAMP_KEEP_TEST_OUTPUT")) fs::remove_all(dir);
}

TEST(DetectorNoisePlot, BadOptionsAndPaths) {
  DetectorNoisePlotOptions o;
  o.panel_width = 50;
  test::ExpectError([&] { DrawDetectorNoisePlot(GroundTruthModel(), o); }, {"DetectorNoisePlotOptions.panel_width"});
  o = DetectorNoisePlotOptions();
  o.header_height = 5;
  test::ExpectError([&] { o.Check(); }, {"DetectorNoisePlotOptions.header_height"});
  // A folder where the file should be.
  const fs::path dir = fs::temp_directory_path() / ("samp_viz_detector_noise_plot_bad_" + std::to_string(::getpid()));
  fs::create_directories(dir / "model.png");
  test::ExpectError([&] { WriteDetectorNoisePlot((dir / "model.png").string(), GroundTruthModel()); },
                    {"model.png", "is a folder"});
  fs::remove_all(dir);
}

}  // namespace
}  // namespace samp
