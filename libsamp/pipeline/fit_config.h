// OUT/config.json of `samp fit` (docs/fitting.md "Output"): every effective
// option of the run, so that a result can be reproduced. This file owns the
// format: one OptionFields function per options struct lists its fields once
// for the writer and the reader (core/json_fields.h), and the reader fails
// naming the file and the key when a key is missing.
#pragma once

#include <string>

#include "libsamp/core/json_fields.h"
#include "libsamp/data/calibration_option_table.h"
#include "libsamp/data/observation_option_table.h"
#include "libsamp/data/sequence_option_table.h"
#include "libsamp/fit/fit_option_table.h"
#include "libsamp/pipeline/fit_output.h"
#include "libsamp/pipeline/run_fit.h"

namespace samp {

// StereoOptions, RoadPlaneOptions, SequenceOptions: data/sequence_option_table.h; ObservationOptions:
// data/observation_option_table.h; TrackerOptions: data/tracking.h.
// MotionNoise, FitOptions: fit/fit_option_table.h (their option tables).
// RunFitOptions' own fields: pipeline/run_fit_option_table.h.
void OptionFields(OptionsJson& io, RunFitOptions& o);

struct FitConfig {
  RunFitOptions options;
  int model_components = 0;  // of the model file the fit used
  // The detector noise model the run linked and fitted with (self-calibrated,
  // read, or none), as tracks.json records it: with the options, what the
  // run's tracker and detection terms effectively used. Written when origin
  // is set, as "detector_model_used" (the key "detector_model" is the option
  // --detector-model); a config.json without it (earlier samp) reads with
  // origin empty.
  TracksFileDetectorModel detector_model;
};

void WriteFitConfig(const std::string& path, const FitConfig& config);
// Throws samp::Error naming the file and the key when a key is missing.
FitConfig ReadFitConfig(const std::string& path);

}  // namespace samp
