#include "libsamp/eval/eval_option_table.h"

#include <cmath>

namespace samp {

namespace {

// One entry of results.json's "results".
struct ResultEntry {
  std::string name, folder;
};

void OptionFields(OptionsJson& io, ResultEntry& r) {
  io("name", r.name);
  io("folder", r.folder);
}

OptionTable<EvalOptions> MakeEvalTable() {
  using O = EvalOptions;
  OptionTable<O> t("EvalOptions");
  t.Add("headline_tau", &O::headline_tau, "headline tau of the tables, m (one of the taus)")
      .Flag("tau")
      .Positive()
      .Rule("one of the taus", [](const O& o) {
        for (double tau : o.taus) {
          if (std::abs(tau - o.headline_tau) < 1e-9) return true;
        }
        return false;
      });
  t.Add("distance_window", &O::distance_window, "width of the pose distance windows, m").Flag("window").Positive();
  t.Add("min_segment_pixels", &O::min_segment_pixels, "evaluate car-frames with at least this many visible pixels")
      .Flag("min-pixels")
      .AtLeast(1);
  t.Add("min_iou", &O::min_iou, "per-track matching: 2D IoU needed to match a box to the truth")
      .Positive()
      .AtMost(1);
  t.Add("per_frame_distance", &O::per_frame_distance,
        "per-frame matching and tracking figures: largest distance of a box's origin to the true car's, m")
      .Flag("match-distance")
      .Positive();
  t.Add("stereo_baseline", &O::stereo_baseline, "the raw-stereo shape baseline").OffFlag("no-stereo");
  t.Add("detection_baseline", &O::detection_baseline, "the input-detection pose baseline").OffFlag("no-detections");
  t.Add("min_box_height_px", &O::min_box_height_px,
        "KITTI tracking's layout: a true car is evaluated when its 2D box is at least this tall, px")
      .Flag("min-box-height")
      .NonNegative();
  t.Add("max_occlusion", &O::max_occlusion, "... its occlusion level at most this (0-3)").NonNegative();
  t.Add("max_truncation", &O::max_truncation, "... and its truncation at most this").AtLeast(0).AtMost(1);
  t.Add("detections_path", &O::detections_path,
        "KITTI tracking's layout: the detections of the detection baseline, a file (one sequence) or a folder "
        "with <seq>.txt (formats of samp fit --detections)")
      .Flag("detections");
  t.Add("num_threads", &O::num_threads, "worker threads (0 = all cores)").Flag("threads").NonNegative();
  return t;
}

}  // namespace

const OptionTable<EvalOptions>& EvalOptionTable() {
  static const OptionTable<EvalOptions> table = MakeEvalTable();
  return table;
}

void OptionFields(OptionsJson& io, EvalOptions& o) {
  EvalOptionTable().Json(io, o);
  io("sequences", o.sequences);
  io("taus", o.taus);
  std::vector<ResultEntry> results;
  for (const auto& [name, folder] : o.results) results.push_back({name, folder});
  io.Array("results", results);
  if (!io.writing()) {
    o.results.clear();
    for (const ResultEntry& r : results) o.results.emplace_back(r.name, r.folder);
  }
}

}  // namespace samp
