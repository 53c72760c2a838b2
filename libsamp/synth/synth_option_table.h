// The option tables of the scene generator (core/option_table.h): every field
// of SynthOptions, StreetOptions and DetectorModelOptions declared once, with
// its command-line name, help and rule. They drive the structs' Check(), the
// options in a synthesized sequence's config.json (SynthOptions::ToJson), the
// options of `samp synth` and the option list of docs/synthetic.md
// (`samp synth --help-options markdown`).
#pragma once

#include "libsamp/core/option_table.h"
#include "libsamp/synth/synth_options.h"

namespace samp {

// Built once; the same table for every call. SynthOptions' table holds the
// street's and the detector's as "street.*" and "detector.*" (command-line
// names without a prefix and with "det-"); output_folder and show_progress
// are not options of a scene and are not in it.
const OptionTable<StreetOptions>& StreetOptionTable();
const OptionTable<DetectorModelOptions>& DetectorModelOptionTable();
const OptionTable<SynthOptions>& SynthOptionTable();

// The JSON of the options through their tables (core/json_fields.h).
void OptionFields(OptionsJson& io, StreetOptions& o);
void OptionFields(OptionsJson& io, DetectorModelOptions& o);
void OptionFields(OptionsJson& io, SynthOptions& o);

}  // namespace samp
