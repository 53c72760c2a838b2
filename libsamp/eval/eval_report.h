// The writers of `samp eval`'s outputs (docs/evaluation.md): the Markdown
// tables, the CSV and JSON files and the plots of an EvalResults. The one
// owner of these files' formats; nothing here computes a score.
#pragma once

#include <string>

#include "libsamp/eval/evaluation.h"

namespace samp {

// The tables of results.md (shape and pose under both matchings, tracking,
// per-car diagnostics).
std::string EvalMarkdown(const EvalOptions& options, const EvalResults& results);

// Writes OUT = options.output_folder (created if missing): results.md
// (results.summary.markdown), shape.csv, pose.csv, per_object.csv,
// per_car.csv, tracking.csv, results.json and the plots f1_vs_tau.png,
// accuracy_vs_tau.png, completeness_vs_tau.png, translation_vs_distance.png,
// yaw_vs_distance.png. Each file is replaced atomically.
void WriteEvalReport(const EvalOptions& options, const EvalResults& results);

}  // namespace samp
