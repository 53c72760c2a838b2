// The option table of the scanner (core/option_table.h): every field of
// ScanOptions declared once, with its command-line name, help and rule. It
// drives ScanOptions::Check(), OptionFields (the "scan" object of the trainer
// options a model file stores), `samp train`'s scan options and their list in
// docs/training.md (`samp train --help-options markdown`).
#pragma once

#include "libsamp/core/option_table.h"
#include "libsamp/scan/scanner.h"

namespace samp {

// Built once; the same table for every call.
const OptionTable<ScanOptions>& ScanOptionTable();

// The JSON of the options through the table (core/json_fields.h).
void OptionFields(OptionsJson& io, ScanOptions& o);

}  // namespace samp
