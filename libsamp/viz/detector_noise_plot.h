// The picture of a detector noise model (data/detector_noise.h): the error
// against distance, as `samp calibrate-detector` writes it beside the model's
// JSON (docs/detector_calibration.md, "The plot").
//
// Four panels, 2 x 2, under a title and above a footer:
//   along the viewing ray | across it
//   vertically            | box size
// Each position panel has the horizontal distance (m) on x and the error (m)
// on y: the measured robust sigma of every distance bin at the bin's mean
// distance, with its number of detections printed above it; the fitted
// sigma(d) = a + b d; and, when the model has biases (ground truth), each
// bin's centre and, along the ray, the model's along_bias. The box-size panel
// has bars of the sigma (and bias) of the height, width and length; the
// model has no per-bin box or yaw statistics, so the yaw sigma, the flip,
// miss and false-positive rates and the sample counts are in the footer's two
// lines.
//
// Pure functions of their arguments; thread-safe.
#pragma once

#include <string>

#include "libsamp/data/detector_noise.h"
#include "libsamp/viz/image.h"

namespace samp {

struct DetectorNoisePlotOptions {
  // One panel's size, px; the figure is 2 panels wide and 2 high.
  int panel_width = 640;
  int panel_height = 440;
  // The bands above and below the panels (title; footer), px.
  int header_height = 44;
  int footer_height = 56;
  // Tick labels, px (axis labels +1, panel titles +4).
  double font_px = 14.0;
  // The figure's title; "" = "Detector noise model (<model.source>)".
  std::string title;

  // The figure's size: 2 panel_width x (header + 2 panel_height + footer).
  int Width() const { return 2 * panel_width; }
  int Height() const { return header_height + 2 * panel_height + footer_height; }
  // Throws samp::Error naming the field and the rule.
  void Check() const;
};

// Throws samp::Error on invalid options.
RgbImage DrawDetectorNoisePlot(const DetectorNoiseModel& model, const DetectorNoisePlotOptions& options = {});

// Draws and writes the PNG atomically (WritePng); throws samp::Error naming
// `path` when it cannot be written.
void WriteDetectorNoisePlot(const std::string& path, const DetectorNoiseModel& model,
                            const DetectorNoisePlotOptions& options = {});

}  // namespace samp
