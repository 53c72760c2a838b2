// The option tables of reading a sequence (core/option_table.h): every field
// of StereoOptions (the disparity samp computes when a frame has none), of
// RoadPlaneOptions (the road plane it estimates when a frame has none) and the
// scalar fields of SequenceOptions (detections, scores, frames) declared once,
// with its command-line name, help and rule. They drive the structs' Check(),
// OptionFields (config.json's "sequence" with its "stereo" and "road_plane"),
// `samp fit`'s --stereo-*, --road-* and input options and their lists in
// docs/sequence_format.md (`samp fit --help-options stereo-markdown`,
// `road-markdown`, `input-markdown`).
#pragma once

#include "libsamp/core/option_table.h"
#include "libsamp/data/road_plane.h"
#include "libsamp/data/sequence.h"
#include "libsamp/data/stereo.h"

namespace samp {

// Built once; the same table for every call.
const OptionTable<StereoOptions>& StereoOptionTable();
const OptionTable<RoadPlaneOptions>& RoadPlaneOptionTable();
// SequenceOptions' own scalar fields (not its nested option structs, its
// object types or its image budget).
const OptionTable<SequenceOptions>& SequenceOptionTable();

// The JSON of the options through the tables (core/json_fields.h).
void OptionFields(OptionsJson& io, StereoOptions& o);
void OptionFields(OptionsJson& io, RoadPlaneOptions& o);
// The nested structs, the table's fields and the object types.
void OptionFields(OptionsJson& io, SequenceOptions& o);

}  // namespace samp
