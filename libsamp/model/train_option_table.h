// The option table of a training run (core/option_table.h): TrainOptions' own
// fields (CAD folder, manifest, preset, output paths, the car grid's voxel
// size, the scan resolution, size variants, threads) declared once, with their
// command-line names, help and rules. It drives TrainOptions::Check() (before
// the nested structs' own), the trainer options a model file stores
// (TrainOptions::ToJson; output paths and threads are not stored), `samp
// train`'s run options and their list in docs/training.md (`samp train
// --help-options run-markdown`). ScanOptions, SdfOptions, SdfQualityOptions
// and PcaOptions have their own tables.
#pragma once

#include "libsamp/core/option_table.h"
#include "libsamp/model/trainer.h"

namespace samp {

// Built once; the same table for every call.
const OptionTable<TrainOptions>& TrainOptionTable();

// The trainer options a model file stores (TrainOptions::ToJson): the table's
// fields, the grid and the nested structs.
void OptionFields(OptionsJson& io, TrainOptions& o);

}  // namespace samp
