// The option tables of the detector's noise model estimation (core/option_table.h):
// every field of DetectorNoiseOptions, BoxConventionOptions and CalibrationOptions declared once, with its
// command-line name, help and rule. They drive the structs' Check(),
// OptionFields (config.json's "calibration", written when it differs from the
// defaults), `samp fit`'s --calibration-* options, `samp calibrate-detector`'s
// noise options and their lists in docs/detector_calibration.md
// (`samp fit --help-options calibration-markdown`).
#pragma once

#include "libsamp/core/option_table.h"
#include "libsamp/data/detector_noise.h"

namespace samp {

// Built once; the same table for every call.
const OptionTable<DetectorNoiseOptions>& DetectorNoiseOptionTable();
const OptionTable<BoxConventionOptions>& BoxConventionOptionTable();
// With the noise options (no prefix) and the box options ("box-") nested.
const OptionTable<CalibrationOptions>& CalibrationOptionTable();

// The JSON of the options through the tables (core/json_fields.h).
void OptionFields(OptionsJson& io, DetectorNoiseOptions& o);
void OptionFields(OptionsJson& io, BoxConventionOptions& o);
void OptionFields(OptionsJson& io, CalibrationOptions& o);

}  // namespace samp
