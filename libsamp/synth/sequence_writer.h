// Writing one synthetic sequence (internal to libsamp/synth): the files
// `samp fit` reads (calib, poses, stereo images, disparity, planes, detections)
// and the ground truth in SEQ/gt/ (labels, depth, object map, meshes, cars.json),
// each written atomically (docs/synthetic.md "Files").
#pragma once

#include "libsamp/core/progress.h"
#include "libsamp/synth/scene.h"

namespace samp::synth {

// Renders and writes sequence `sequence_index` of `scene` to
// <output_folder>/<%06d of first_sequence + sequence_index>; ticks `progress`
// (may be null) once per frame.
SynthSequenceInfo WriteSequence(const SynthOptions& options, const Scene& scene, int sequence_index,
                                Progress* progress);

}  // namespace samp::synth
