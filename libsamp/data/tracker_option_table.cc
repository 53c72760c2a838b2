#include "libsamp/data/tracker_option_table.h"

namespace samp {

namespace {

OptionTable<TrackerOptions> MakeTrackerTable() {
  using T = TrackerOptions;
  OptionTable<T> t("TrackerOptions");
  t.Add("along_sigma_a", &T::along_sigma_a,
        "detector std. dev. along the horizontal viewing ray: a + b d + c d^2, m (d = distance): a")
      .Positive();
  t.Add("along_sigma_b", &T::along_sigma_b, "... along the ray: b").NonNegative();
  t.Add("along_sigma_c", &T::along_sigma_c, "... along the ray: c").NonNegative();
  t.Add("across_sigma_a", &T::across_sigma_a, "detector std. dev. across the ray: a + b d, m: a").Positive();
  t.Add("across_sigma_b", &T::across_sigma_b, "... across the ray: b").NonNegative();
  t.Add("vertical_sigma_a", &T::vertical_sigma_a, "detector vertical std. dev.: a + b d, m: a").Positive();
  t.Add("vertical_sigma_b", &T::vertical_sigma_b, "... vertical: b").NonNegative();
  t.Add("size_sigma", &T::size_sigma, "std. dev. of each detected box dimension h, w, l, m").Positive();
  t.Add("yaw_sigma_deg", &T::yaw_sigma_deg, "std. dev. of the detected yaw modulo 180 deg, deg")
      .Positive()
      .Deprecated("yaw-sigma");
  t.Add("acceleration_sigma", &T::acceleration_sigma,
        "white acceleration noise of the constant-velocity model, m/s^2")
      .Positive();
  t.Add("max_speed", &T::max_speed, "a new track's velocity has std. dev. max_speed / 2 per axis, m/s")
      .Positive();
  t.Add("gate_chi2", &T::gate_chi2, "gate on the squared Mahalanobis distance of the ground-plane position (2 dof)")
      .Positive()
      .Deprecated("gate");
  t.Add("size_gate_chi2", &T::size_gate_chi2, "gate on the box size's squared Mahalanobis distance (3 dof)")
      .Positive();
  t.Add("height_gate_chi2", &T::height_gate_chi2,
        "gate on the bottom centre's height, squared Mahalanobis distance (1 dof)")
      .Positive();
  t.Add("yaw_gate_deg", &T::yaw_gate_deg,
        "largest axis difference (yaw modulo 180 deg) of a detection to its track, deg")
      .Above(0)
      .AtMost(90)
      .Deprecated("yaw-gate");
  t.Add("tentative_penalty", &T::tentative_penalty,
        "cost penalty of a tentative track, so that a confirmed one wins a contested detection")
      .NonNegative();
  t.Add("confirm_hits", &T::confirm_hits, "detections that confirm a new track").AtLeast(1);
  t.Add("tentative_max_misses", &T::tentative_max_misses,
        "a tentative track ends after more consecutive missed frames")
      .AtLeast(0);
  t.Add("max_misses", &T::max_misses, "a confirmed track ends after more consecutive missed frames").AtLeast(0);
  t.Add("join_fragments", &T::join_fragments, "join fragments whose constant-velocity fits agree")
      .Deprecated("join", "true")
      .Deprecated("--no-tracker-join", "false");
  t.Add("max_join_gap", &T::max_join_gap, "fragments are joined across at most this many missed frames")
      .AtLeast(0);
  t.Add("join_gate_chi2", &T::join_gate_chi2, "largest link cost of a join (squared Mahalanobis units)")
      .Positive()
      .Deprecated("join-gate");
  t.Add("resolve_switches", &T::resolve_switches,
        "swap the tails of two tracks where that resolves an identity switch")
      .Deprecated("swaps", "true")
      .Deprecated("--no-tracker-swaps", "false");
  t.Add("swap_margin", &T::swap_margin, "a swap must lower the two links' cost by this much").NonNegative();
  t.Add("fit_window", &T::fit_window, "detections per side in the constant-velocity fits of the second stage")
      .AtLeast(1);
  t.Add("min_track_length", &T::min_track_length,
        "tracks with fewer detections are dropped (1 keeps single detections, e.g. for --single-frame)")
      .AtLeast(1)
      .Flag("--min-track-length");
  t.Add("frame_rate_hz", &T::frame_rate_hz, "frames per second of the sequences").Positive().Flag("--frame-rate");
  t.Add("warn_median_length", &T::warn_median_length,
        "the summary warns when a sequence's median track is shorter (frames)")
      .AtLeast(0);
  t.AddOptional("robust_cues", &T::robust_cues,
                "one cue (box size, height or yaw) far outside its gate costs its gate value instead of "
                "forbidding the pair when position and motion agree");
  return t;
}

}  // namespace

const OptionTable<TrackerOptions>& TrackerOptionTable() {
  static const OptionTable<TrackerOptions> table = MakeTrackerTable();
  return table;
}

void TrackerOptions::Check() const { TrackerOptionTable().Check(*this); }

void OptionFields(OptionsJson& io, TrackerOptions& o) { TrackerOptionTable().Json(io, o); }

}  // namespace samp
