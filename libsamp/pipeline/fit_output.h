// Outputs of a fit (docs/fitting.md, "Output"): KITTI tracking result lines,
// the fitted surface and the aligned observations as PLY, and tracks.json
// (its writer and its one reader; config.json is pipeline/fit_config.h).
// Every file is written atomically. Free functions without shared state:
// thread-safe for distinct paths.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "libsamp/core/grid_spec.h"
#include "libsamp/core/json_fields.h"
#include "libsamp/core/mesh.h"
#include "libsamp/data/detector_noise.h"
#include "libsamp/data/track.h"
#include "libsamp/fit/fitter.h"

namespace samp {

// Box of the fitted shape in the object frame: extent of phi_z < 0.
AlignedBox FittedBox(const ShapeLookup& lookup, const Eigen::VectorXd& z);

// The axes along which `box` (a FittedBox) reaches the limits of the model's
// grid, within half a voxel: "length" (x), "height" (y), "width" (z); empty
// when it lies inside or is empty. A shape whose inside fills the grid along
// an axis is cut by the grid, not by a surface: the fit has pushed the code
// out of what the model spans (a vehicle larger than, or unlike, its training
// cars), and its shape and pose are unreliable (docs/fitting.md, "Shapes at
// the grid's limits").
std::vector<std::string> GridLimitsReached(const AlignedBox& box, const GridSpec& grid);

// KITTI tracking result of every frame of `fit` (camera frame of that frame,
// using track.frames[k].world_from_camera): x y z = object origin, ry = yaw,
// h w l = extent of the fitted box along object y, z, x, alpha = ry -
// atan2(x, z), 2D box = projection of the fitted 3D box (its 8 corners)
// clipped to the image, score = the detection's. `fit` and `track` must have
// the same frames.
std::vector<ObjectLabel> FitToLabels(const TrackFit& fit, const Track& track,
                                     const ShapeLookup& lookup);

// Zero level set of phi_z in the object frame (OpenVDB mesher,
// libsamp/sdf/surface.h). Empty when the shape has no inside.
Mesh FittedSurface(const ShapeLookup& lookup, const Eigen::VectorXd& z);

// The associated points of every frame moved into the object frame by that
// frame's fitted pose, coloured by frame (blue = first, red = last).
PointCloud AlignedObservations(const TrackFit& fit);

// JSON record of one fitted track (fields in docs/fitting.md) and its reader
// (the inverse, without points_in_world); `fields` names the file and key in errors.
nlohmann::json TrackFitToJson(const TrackFit& fit, const AlignedBox& box);
TrackFit TrackFitFromJson(const JsonFields& fields, AlignedBox* box = nullptr);

// The paths of a fit's output folder OUT (docs/fitting.md "Output"):
// OUT/tracks.json, OUT/label_02/<seq>.txt, and the meshes of track <id>:
// OUT/meshes/track_<id>.ply and track_<id>_points.ply, in OUT/meshes/<seq>/
// when the fit had several sequences.
std::string FitTracksPath(const std::string& out);
std::string FitLabelsPath(const std::string& out, const std::string& seq);
// A track's mesh path relative to OUT, without ".ply": "meshes/[<seq>/]track_<id>".
std::string FitMeshStem(const std::string& seq, int track_id, bool per_sequence_folder);

// OUT/tracks.json (docs/fitting.md "Output").
struct TracksFileTrack {
  TrackFit fit;              // frames without points_in_world
  AlignedBox box;            // of the fitted shape; empty when it has no inside
  std::vector<std::string> at_grid_limit;  // GridLimitsReached(box); empty = inside the grid
  std::string mesh, points;  // relative to OUT; empty when no meshes were written
};
struct TracksFileSequence {
  std::string directory;
  std::string name;
  bool ok = false;
  std::string error;                        // why the sequence failed (when !ok)
  std::string input;                        // SequenceSummary::BriefReport()
  std::vector<std::string> input_messages;  // the reader's substitutions
  nlohmann::json tracking;                  // TrackingSummary::ToJson() (when ok)
  std::vector<TracksFileTrack> tracks;
  std::vector<std::string> failed_tracks;   // "track <id>: message"
};
// The detector noise model the run linked and fitted with ("detector_model"
// in tracks.json): one per run, the same for every sequence of it.
struct TracksFileDetectorModel {
  // "self-calibration" (estimated from the run's sequences), "file" (read
  // from RunFitOptions::detector_model_path) or "none" (the tracker's and the
  // fit's detector options as given). Empty: not recorded (a tracks.json of a
  // samp before the key; not written).
  std::string origin;
  std::string file;    // origin "file": the model file read
  std::string reason;  // origin "none": why the run used no model
  // Unless origin is "none": the model as OUT/detector_model.json holds it,
  // written and read by its one owner (DetectorNoiseModel::ToJson,
  // DetectorNoiseModelFromJson), sample counts and notes included.
  DetectorNoiseModel model;
};
// "detector_model" of tracks.json and config.json: how the run got its
// detector noise model and, unless it used none, the model in the format of
// its one owner (DetectorNoiseModel::ToJson, the text of
// OUT/detector_model.json) as a nested object. `path` names the file in
// errors; throws samp::Error for an unknown origin.
nlohmann::json DetectorModelRecordToJson(const TracksFileDetectorModel& record, const std::string& path);
// Throws samp::Error naming the key for a bad origin or a malformed model.
TracksFileDetectorModel DetectorModelRecordFromJson(const JsonFields& j);

struct TracksFile {
  std::string model;  // the model file the fit used
  TracksFileDetectorModel detector_model;
  std::vector<TracksFileSequence> sequences;
};
void WriteTracksFile(const std::string& path, const TracksFile& file);
// Throws samp::Error naming the file and the key when a key is missing, or
// "detector_model" is malformed (it may be absent: origin stays empty).
TracksFile ReadTracksFile(const std::string& path);

}  // namespace samp
