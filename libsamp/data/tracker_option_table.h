// The option table of samp's tracker (core/option_table.h): every field of
// TrackerOptions declared once, with its command-line name (prefixed
// "tracker-" by `samp fit`), help and rule. It drives TrackerOptions::Check(),
// OptionFields (config.json's "sequence.tracker"), the tracker options of
// `samp fit` and their list in docs/fitting.md.
#pragma once

#include "libsamp/core/option_table.h"
#include "libsamp/data/tracking.h"

namespace samp {

// Built once; the same table for every call.
const OptionTable<TrackerOptions>& TrackerOptionTable();

}  // namespace samp
