// The option tables of reading a sequence (core/option_table.h): every field
// of StereoOptions (the disparity samp computes when a frame has none), of
// RoadPlaneOptions (the road plane it estimates when a frame has none) and the
// own fields of SequenceOptions (detections, scores, frames, object types) declared once,
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
// SequenceOptions' own fields (not its nested option structs or its image budget).
const OptionTable<SequenceOptions>& SequenceOptionTable();

// The JSON of the options through the tables (core/json_fields.h).
void OptionFields(OptionsJson& io, StereoOptions& o);
void OptionFields(OptionsJson& io, RoadPlaneOptions& o);
// The nested structs and the table's fields.
void OptionFields(OptionsJson& io, SequenceOptions& o);

}  // namespace samp
