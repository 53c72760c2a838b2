// The option table of the PCA (core/option_table.h): PcaOptions' one field
// declared once. It drives PcaOptions::Check(), OptionFields (the "pca" object
// of the trainer options a model file stores), `samp train -R` and its line in
// docs/training.md (`samp train --help-options markdown`).
#pragma once

#include "libsamp/core/option_table.h"
#include "libsamp/model/pca.h"

namespace samp {

// Built once; the same table for every call.
const OptionTable<PcaOptions>& PcaOptionTable();

// The JSON of the options through the table (core/json_fields.h).
void OptionFields(OptionsJson& io, PcaOptions& o);

}  // namespace samp
