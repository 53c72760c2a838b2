// The option tables of the SDF (core/option_table.h): every field of
// SdfOptions and of the trainer's quality gate SdfQualityOptions declared
// once, with its command-line name, help and rule. They drive the structs'
// Check(), OptionFields (the "sdf" and "gate" objects of the trainer options a
// model file stores), `samp train`'s SDF and --gate-* options and their lists
// in docs/training.md (`samp train --help-options markdown`, `gate-markdown`).
#pragma once

#include "libsamp/core/option_table.h"
#include "libsamp/sdf/sdf.h"

namespace samp {

// Built once; the same table for every call.
const OptionTable<SdfOptions>& SdfOptionTable();
const OptionTable<SdfQualityOptions>& SdfQualityOptionTable();

// The sign's name in files and on the command line ("carving",
// "carving_and_closing") and back (samp::Error for another name).
const char* SdfSignName(SdfOptions::Sign sign);
SdfOptions::Sign ParseSdfSign(const std::string& name);

// The JSON of the options through the tables (core/json_fields.h).
void OptionFields(OptionsJson& io, SdfOptions& o);
void OptionFields(OptionsJson& io, SdfQualityOptions& o);

}  // namespace samp
