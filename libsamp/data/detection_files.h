// Detection files of a whole sequence, as public detectors and trackers
// distribute them (docs/sequence_format.md, "Detections"); the owner of the
// comma-separated AB3DMOT format (reader and writer). The per-frame KITTI
// object files and the KITTI tracking lines are kitti_io.h's.
//
//   kitti-object    one file per frame, "type trunc occ alpha x1 y1 x2 y2 h w l x y z ry [score]"
//   kitti-tracking  one file per sequence, "frame id type trunc occ alpha x1 y1 x2 y2 h w l x y z ry [score]"
//                   (a tracker's result file or label_02; the ids are ignored)
//   ab3dmot         one file per sequence, "frame,type,x1,y1,x2,y2,score,h,w,l,x,y,z,ry,alpha"
//                   with type 1 = Pedestrian, 2 = Car, 3 = Cyclist
//
// Readers throw samp::Error naming file:line for the first bad line (column
// count, unknown class id, a value that is not a finite number, the label
// plausibility checks of kitti_io.h). Free functions: thread-safe.
#pragma once

#include <string>
#include <vector>

#include "libsamp/data/track.h"

namespace samp {

enum class DetectionFormat { kAuto, kKittiObject, kKittiTracking, kAb3dmot };

// "auto", "kitti-object", "kitti-tracking", "ab3dmot"; throws naming the choices.
DetectionFormat ParseDetectionFormat(const std::string& name);
std::string DetectionFormatName(DetectionFormat format);

// The format of a detection file from its first non-blank line: commas ->
// ab3dmot; 17 or 18 columns -> kitti-tracking; 15 or 16 -> kitti-object.
// kAuto for an empty file; an error naming file:line for anything else.
DetectionFormat SniffDetectionFormat(const std::string& path);

// A per-sequence detection file (kitti-tracking or ab3dmot; kAuto sniffs).
// Every label has its frame; track ids are -1. kitti-object is refused (one
// frame per file: give a folder of them).
std::vector<ObjectLabel> ReadDetectionFile(const std::string& path, DetectionFormat format);

// AB3DMOT's comma-separated lines; types other than the three are refused.
std::vector<ObjectLabel> ReadAb3dmotDetections(const std::string& path);
void WriteAb3dmotDetections(const std::string& path, const std::vector<ObjectLabel>& labels);

}  // namespace samp
