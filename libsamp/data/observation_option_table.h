// The option table of the candidate points (core/option_table.h): every field
// of ObservationOptions declared once, with its command-line name, help and
// rule. It drives ObservationOptions::Check(), OptionFields (config.json's
// "sequence.observations"), the candidate-point options of `samp fit` and
// their list in docs/fitting.md (`samp fit --help-options observation-markdown`).
#pragma once

#include "libsamp/core/option_table.h"
#include "libsamp/data/observations.h"

namespace samp {

// Built once; the same table for every call.
const OptionTable<ObservationOptions>& ObservationOptionTable();

// The JSON of the options through the table (core/json_fields.h).
void OptionFields(OptionsJson& io, ObservationOptions& o);

}  // namespace samp
