#include "libsamp/data/sequence_option_table.h"

#include <algorithm>

#include "libsamp/data/observation_option_table.h"
#include "libsamp/data/tracker_option_table.h"

namespace samp {

namespace {

OptionTable<StereoOptions> MakeStereoTable() {
  using O = StereoOptions;
  OptionTable<O> t("StereoOptions");
  t.Add("min_disparity", &O::min_disparity, "smallest disparity searched, px");
  t.Add("num_disparities", &O::num_disparities, "number of disparities searched, px")
      .Positive()
      .Rule("a multiple of 16", [](const O& o) { return o.num_disparities % 16 == 0; });
  t.Add("block_size", &O::block_size, "matching block side, px")
      .AtLeast(1)
      .AtMost(11)
      .Rule("odd", [](const O& o) { return o.block_size % 2 == 1; });
  t.Add("p1", &O::p1, "smoothness penalty of a disparity change of 1 px (0 = OpenCV's 8 channels block^2)")
      .NonNegative();
  t.Add("p2", &O::p2, "smoothness penalty of a change above 1 px (0 = OpenCV's 32 channels block^2)")
      .NonNegative()
      .Rule("> p1 when both are set", [](const O& o) { return o.p1 == 0 || o.p2 == 0 || o.p2 > o.p1; });
  t.Add("disp12_max_diff", &O::disp12_max_diff, "maximal left-right consistency difference, px (< 0: no check)");
  t.Add("pre_filter_cap", &O::pre_filter_cap, "clipping of the prefiltered image derivatives").Positive();
  t.Add("uniqueness_ratio", &O::uniqueness_ratio, "the best cost beats the second best by this margin, %")
      .NonNegative()
      .Below(100);
  t.Add("speckle_window_size", &O::speckle_window_size,
        "regions smaller than this (px) with a disparity spread above speckle_range are invalidated (0 = off)")
      .NonNegative();
  t.Add("speckle_range", &O::speckle_range, "maximal disparity spread within a speckle region, px").NonNegative();
  t.Add("mode", &O::mode, "OpenCV's SGBM mode: sgbm (5 directions), hh (8, more memory), 3way (fast), hh4")
      .Choices({"sgbm", "hh", "3way", "hh4"});
  return t;
}

OptionTable<RoadPlaneOptions> MakeRoadPlaneTable() {
  using O = RoadPlaneOptions;
  OptionTable<O> t("RoadPlaneOptions");
  t.Add("iterations", &O::iterations, "RANSAC hypotheses (3-point samples)").Positive();
  t.Add("inlier_threshold", &O::inlier_threshold, "point-to-plane distance of an inlier, m").Positive();
  t.Add("min_point_height_below_camera", &O::min_point_height_below_camera,
        "only points this far below the camera are used, m");
  t.Add("max_depth", &O::max_depth, "... and nearer than this, m").Positive();
  t.Add("max_tilt_deg", &O::max_tilt_deg, "hypotheses whose normal is further from the camera's up axis are rejected, deg")
      .Positive()
      .Below(90);
  t.Add("min_camera_height", &O::min_camera_height, "accepted camera heights above the plane: from, m")
      .Rule("< max_camera_height", [](const O& o) { return o.min_camera_height < o.max_camera_height; });
  t.Add("max_camera_height", &O::max_camera_height, "... to, m");
  t.Add("max_points", &O::max_points, "at most this many points are used (seeded subsample)").AtLeast(3);
  t.Add("min_inliers", &O::min_inliers, "the fit fails with fewer inliers").AtLeast(3);
  t.Add("seed", &O::seed, "seed of the subsample and of RANSAC").Internal();
  return t;
}

OptionTable<SequenceOptions> MakeSequenceTable() {
  using O = SequenceOptions;
  OptionTable<O> t("SequenceOptions");
  t.Add("tracking_labels_path", &O::tracking_labels_path,
        "a KITTI tracking label file giving the tracks instead of samp's tracker (samp fit --tracks, one per "
        "sequence)")
      .Internal();
  t.Add("min_detection_score", &O::min_detection_score, "detections with a lower score are ignored")
      .Flag("min-score");
  t.Add("first_frame", &O::first_frame, "only frames from this one (-1 = the first; samp fit --frames FIRST-LAST)")
      .Internal()
      .AtLeast(-1);
  t.Add("last_frame", &O::last_frame, "... to this one (-1 = the last)")
      .Internal()
      .AtLeast(-1)
      .Rule(">= first_frame", [](const O& o) { return o.last_frame < 0 || o.first_frame < 0 || o.first_frame <= o.last_frame; });
  t.AddOptional("detections", &O::detections_path,
                "detections instead of the layout's: a file (kitti-tracking or ab3dmot lines) for one sequence, or "
                "a folder with <seq>.txt per sequence or <seq>_<ff>.txt per frame (KITTI object)",
                std::string())
      .Flag("detections");
  t.AddOptional("detection_format", &O::detection_format,
                "format of --detections: auto, kitti-object, kitti-tracking (frame id type ...; ids ignored), "
                "ab3dmot (frame,type,x1,y1,x2,y2,score,h,w,l,x,y,z,ry,alpha; type 2 = car)",
                std::string("auto"))
      .Choices({"auto", "kitti-object", "kitti-tracking", "ab3dmot"});
  t.AddList("object_types", &O::object_types, "object types used, comma-separated, case-insensitive")
      .Flag("types")
      .Separator(',')
      .Rule("a non-empty list of names", [](const O& o) {
        return !o.object_types.empty() &&
               std::none_of(o.object_types.begin(), o.object_types.end(), [](const std::string& type) {
                 return type.empty();
               });
      });
  return t;
}

}  // namespace

const OptionTable<SequenceOptions>& SequenceOptionTable() {
  static const OptionTable<SequenceOptions> table = MakeSequenceTable();
  return table;
}

void OptionFields(OptionsJson& io, SequenceOptions& o) {
  io.Nested("stereo", o.stereo);
  io.Nested("road_plane", o.road_plane);
  io.Nested("observations", o.observations);
  io.Nested("tracker", o.tracker);
  SequenceOptionTable().Json(io, o);
}

const OptionTable<StereoOptions>& StereoOptionTable() {
  static const OptionTable<StereoOptions> table = MakeStereoTable();
  return table;
}

const OptionTable<RoadPlaneOptions>& RoadPlaneOptionTable() {
  static const OptionTable<RoadPlaneOptions> table = MakeRoadPlaneTable();
  return table;
}

void OptionFields(OptionsJson& io, StereoOptions& o) { StereoOptionTable().Json(io, o); }
void OptionFields(OptionsJson& io, RoadPlaneOptions& o) { RoadPlaneOptionTable().Json(io, o); }

}  // namespace samp
