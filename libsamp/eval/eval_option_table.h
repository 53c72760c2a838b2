// The option table of the evaluation (core/option_table.h): every scalar field
// of EvalOptions declared once, with its command-line name, help and rule. It
// drives EvalOptions::Check() (with the checks of its lists: sequences,
// results, taus), EvalOptions::ToJson (results.json's "options"), `samp
// eval`'s options and their list in docs/evaluation.md (`samp eval
// --help-options markdown`).
#pragma once

#include "libsamp/core/option_table.h"
#include "libsamp/eval/eval_options.h"

namespace samp {

// Built once; the same table for every call.
const OptionTable<EvalOptions>& EvalOptionTable();

// The JSON of the options: the table's fields, the sequences, the results as
// [{"name", "folder"}] and the taus (core/json_fields.h).
void OptionFields(OptionsJson& io, EvalOptions& o);

}  // namespace samp
