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
};

void WriteFitConfig(const std::string& path, const FitConfig& config);
// Throws samp::Error naming the file and the key when a key is missing.
FitConfig ReadFitConfig(const std::string& path);

}  // namespace samp
