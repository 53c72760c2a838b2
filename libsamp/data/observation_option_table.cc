#include "libsamp/data/observation_option_table.h"

namespace samp {

namespace {

OptionTable<ObservationOptions> MakeObservationTable() {
  using O = ObservationOptions;
  OptionTable<O> t("ObservationOptions");
  t.Add("box_margin", &O::box_margin,
        "the detection's 2D box is enlarged by this fraction of its width and height on each side")
      .AtLeast(0)
      .AtMost(2);
  t.Add("min_height_above_road", &O::min_height_above_road, "points must lie higher above the road plane, m");
  t.Add("max_distance_to_detection", &O::max_distance_to_detection,
        "candidate gate: points within this distance of the detected box's centre (or of its ray, see "
        "depth_gate_sigmas), m; the fit's first association narrows it to association_radius")
      .Positive();
  t.Add("depth_gate_sigmas", &O::depth_gate_sigmas,
        "... or along a ray passing within that distance, up to this many sigma_d at the centre's depth beyond "
        "it (0 = the sphere alone)")
      .NonNegative();
  t.Add("min_disparity_px", &O::min_disparity_px, "disparities below this are ignored (too far), px")
      .Flag("min-disparity")
      .Positive();
  t.Add("sigma_disparity_px", &O::sigma_disparity_px, "disparity noise for sigma_d = d^2 sigma / (b f), px")
      .Flag("sigma-disparity")
      .Positive();
  t.Add("max_points_per_frame", &O::max_points_per_frame,
        "at most this many candidate points per frame (seeded subsample; 0 = all)")
      .Flag("max-points")
      .NonNegative();
  t.Add("seed", &O::seed, "seed of the subsample, combined with the track id and the frame number").Internal();
  t.Add("nearest_box_claims", &O::nearest_box_claims,
        "a point nearer to another detection's 3D box of the same frame is that car's (docs/fitting.md, "
        "\"Association\"); --shared-points: every track keeps every point of its 2D box (the paper)")
      .OffFlag("shared-points");
  return t;
}

}  // namespace

const OptionTable<ObservationOptions>& ObservationOptionTable() {
  static const OptionTable<ObservationOptions> table = MakeObservationTable();
  return table;
}

void OptionFields(OptionsJson& io, ObservationOptions& o) { ObservationOptionTable().Json(io, o); }

}  // namespace samp
