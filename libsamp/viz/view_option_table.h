// The option tables of drawing a fit (core/option_table.h): the fields of
// LoadFitRunOptions (reading a fit's output), FitHtmlOptions (its viewer page)
// and FitVisualsOptions (which of pictures and page, where) declared once,
// with their command-line names, help and rules. They drive the structs'
// Check() (FitVisualsOptions' after its table: pictures or page asked for,
// the pictures' own options), `samp view`'s options and their list in
// docs/fitting.md, "Viewer" (`samp view --help-options markdown`). Nothing
// stores these options; the tables write no file.
#pragma once

#include "libsamp/core/option_table.h"
#include "libsamp/viz/fit_pictures.h"
#include "libsamp/viz/fit_run.h"
#include "libsamp/viz/html_viewer.h"

namespace samp {

// Built once; the same table for every call.
const OptionTable<LoadFitRunOptions>& LoadFitRunOptionTable();
const OptionTable<FitHtmlOptions>& FitHtmlOptionTable();
// With the load (no prefix) and page (no prefix) options nested.
const OptionTable<FitVisualsOptions>& FitVisualsOptionTable();

}  // namespace samp
