// The option table of a `samp fit` run (core/option_table.h): RunFitOptions'
// own fields (model, sequences, tracking label files, output folder, threads,
// meshes, link-only, self-calibration, detector model and its plot) declared
// once, with their command-line names, help and rules. It drives
// RunFitOptions::Check() (before the nested structs' own), config.json's
// top-level keys (pipeline/fit_config.h), `samp fit`'s run options and their
// list in docs/fitting.md (`samp fit --help-options run-markdown`). The nested
// FitOptions, SequenceOptions and CalibrationOptions have their own tables.
#pragma once

#include "libsamp/core/option_table.h"
#include "libsamp/pipeline/run_fit.h"

namespace samp {

// Built once; the same table for every call.
const OptionTable<RunFitOptions>& RunFitOptionTable();

}  // namespace samp
