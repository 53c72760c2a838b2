#include "libsamp/data/calibration_option_table.h"

#include <algorithm>
#include <functional>

namespace samp {

namespace {

OptionTable<DetectorNoiseOptions> MakeDetectorNoiseTable() {
  using O = DetectorNoiseOptions;
  OptionTable<O> t("DetectorNoiseOptions");
  t.AddList("bin_edges", &O::bin_edges, "distance bin edges, m, increasing, comma-separated (the last bin is open)")
      .Separator(',')
      .NonNegative()
      .Rule("a non-empty increasing list", [](const O& o) {
        return !o.bin_edges.empty() && std::adjacent_find(o.bin_edges.begin(), o.bin_edges.end(),
                                                           std::greater_equal<double>()) == o.bin_edges.end();
      });
  t.Add("min_track_detections", &O::min_track_detections, "tracks with fewer detections are not used").AtLeast(3);
  t.Add("min_bin_count", &O::min_bin_count, "a distance bin with fewer detections does not enter the sigma(d) fit")
      .AtLeast(2);
  t.Add("min_bin_tracks", &O::min_bin_tracks,
        "... or with detections of fewer tracks (self-calibration) or true cars (calibrate-detector)")
      .AtLeast(1);
  t.Add("min_samples", &O::min_samples, "a term with fewer samples keeps its default (noted)").AtLeast(2);
  t.Add("smoother_degree", &O::smoother_degree,
        "degree of the robust smoother of a track's bottom centre in time (1 constant velocity, 2 constant "
        "acceleration)")
      .AtLeast(1)
      .AtMost(2);
  t.Add("trim_sigmas", &O::trim_sigmas, "cut-off of the residuals that enter the trimmed statistics, robust sigmas")
      .AtLeast(1.5);
  t.Add("correct_correlation", &O::correct_correlation,
        "measure how the errors are correlated between frames and undo what the smoother absorbs of them (off: "
        "white errors)");
  t.Add("correlation_pairs_per_cue", &O::correlation_pairs_per_cue,
        "each cue gets a correlation of its own with at least this many pairs of consecutive detections per cue; "
        "fewer: one correlation measured on all cues together")
      .AtLeast(30);
  return t;
}

OptionTable<BoxConventionOptions> MakeBoxConventionTable() {
  using O = BoxConventionOptions;
  OptionTable<O> t("BoxConventionOptions");
  t.Add("max_distance", &O::max_distance, "a detection is used when its car is within this horizontal distance, m")
      .Positive();
  t.Add("min_points", &O::min_points, "... and at least this many stereo points were associated in its frame")
      .AtLeast(1);
  t.Add("min_cars", &O::min_cars, "the estimate needs this many cars, else the biases stay 0 (noted)").AtLeast(1);
  t.Add("min_detections", &O::min_detections, "... and this many detections").AtLeast(1);
  t.Add("max_end_view_deg", &O::max_end_view_deg,
        "the width is compared where the car's rear or front faces the camera: view angle at most this, deg")
      .AtLeast(0)
      .AtMost(90);
  t.Add("min_side_view_deg", &O::min_side_view_deg, "the length where its side does: view angle at least this, deg")
      .AtLeast(0)
      .AtMost(90);
  t.Add("min_significance", &O::min_significance, "a bias smaller than this many standard errors is taken as 0")
      .NonNegative();
  t.Add("apply_along_bias", &O::apply_along_bias,
        "apply the along-ray bias to the fit (always measured and reported; docs/detector_calibration.md)");
  return t;
}

OptionTable<CalibrationOptions> MakeCalibrationTable() {
  using O = CalibrationOptions;
  OptionTable<O> t("CalibrationOptions");
  t.AddNested("noise", &O::noise, DetectorNoiseOptionTable(), "");
  t.Add("max_iterations", &O::max_iterations, "re-linkings with the estimate at most, to a fixed point").AtLeast(1);
  t.Add("tolerance", &O::tolerance, "the fixed point: every sigma changed by less than this share").Positive();
  t.Add("tracker_sigma_scale", &O::tracker_sigma_scale,
        "the tracker's sigmas are the estimate times this (its filter assumes white noise)")
      .AtLeast(1);
  t.Add("estimate_box_convention", &O::estimate_box_convention,
        "with self-calibration: measure the detector's box convention on the near, well-observed cars fitted to "
        "their points alone, and fit every car with it (docs/detector_calibration.md, \"Box conventions\")")
      .Flag("--estimate-box-convention");
  t.AddNested("box", &O::box, BoxConventionOptionTable(), "box-");
  return t;
}

}  // namespace

const OptionTable<DetectorNoiseOptions>& DetectorNoiseOptionTable() {
  static const OptionTable<DetectorNoiseOptions> table = MakeDetectorNoiseTable();
  return table;
}

const OptionTable<BoxConventionOptions>& BoxConventionOptionTable() {
  static const OptionTable<BoxConventionOptions> table = MakeBoxConventionTable();
  return table;
}

const OptionTable<CalibrationOptions>& CalibrationOptionTable() {
  static const OptionTable<CalibrationOptions> table = MakeCalibrationTable();
  return table;
}

void OptionFields(OptionsJson& io, DetectorNoiseOptions& o) { DetectorNoiseOptionTable().Json(io, o); }

void OptionFields(OptionsJson& io, BoxConventionOptions& o) { BoxConventionOptionTable().Json(io, o); }
void OptionFields(OptionsJson& io, CalibrationOptions& o) { CalibrationOptionTable().Json(io, o); }

}  // namespace samp
