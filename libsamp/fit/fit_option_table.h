// The option tables of the fitter (core/option_table.h): every field of
// FitOptions and MotionNoise declared once, with its command-line name, help
// and rule. They drive FitOptions::Check(), the "fit" object of a fit's
// config.json (pipeline/fit_config.h), the options of `samp fit` and the
// option list of docs/fitting.md (`samp fit --help-options markdown`).
#pragma once

#include "libsamp/core/option_table.h"
#include "libsamp/fit/fit_options.h"

namespace samp {

// Built once; the same table for every call.
const OptionTable<MotionNoise>& MotionNoiseOptionTable();
const OptionTable<FitOptions>& FitOptionTable();

// The JSON of the options through their tables (core/json_fields.h).
void OptionFields(OptionsJson& io, MotionNoise& o);
void OptionFields(OptionsJson& io, FitOptions& o);

}  // namespace samp
