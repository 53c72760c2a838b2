#include "libsamp/pipeline/run_fit_option_table.h"

namespace samp {

namespace {

OptionTable<RunFitOptions> MakeRunFitTable() {
  using O = RunFitOptions;
  OptionTable<O> t("RunFitOptions");
  // The help is samp fit's: a flag that only turns off says so.
  t.Add("model", &O::model_path, "Shape model file (.vdb); default: the shipped model")
      .Flag("model")
      .Rule("given unless link_only", [](const O& o) { return o.link_only || !o.model_path.empty(); });
  t.AddList("sequences", &O::sequences,
            "Sequence directory (docs/sequence_format.md; samp's layout, a KITTI tracking ROOT/image_02/<seq> or a "
            "KITTI stereo ROOT/calib_cam_to_cam/<seq>.txt); repeat for a batch")
      .Flag("seq")
      .Rule("given (at least one --seq)", [](const O& o) { return !o.sequences.empty(); });
  t.AddList("tracking_labels", &O::tracking_labels,
            "KITTI tracking label file giving the tracks (frame track_id ...); repeat once per --seq, in the same "
            "order: the way to plug in another tracker. Without it detections/ are linked into tracks by samp's "
            "tracker (--tracker-* options)")
      .Flag("tracks")
      .Rule("empty or one per sequence",
            [](const O& o) { return o.tracking_labels.empty() || o.tracking_labels.size() == o.sequences.size(); });
  t.Add("output_dir", &O::output_dir,
        "Output directory: written into a temporary folder beside it that replaces it as a whole at the end; must "
        "be new, empty or an earlier samp fit output")
      .Flag("out")
      .Required();
  t.Add("num_threads", &O::num_threads, "Worker threads for sequences and tracks (0 = all cores)")
      .Flag("threads")
      .NonNegative();
  t.Add("write_meshes", &O::write_meshes, "Do not write meshes/ (PLY surfaces and aligned points)")
      .Flag("meshes")
      .OffOnly();
  t.Add("link_only", &O::link_only,
        "Only link detections/ into tracks and write the tracked detections as label_02/<seq>.txt (no model, no "
        "fit; for samp eval's tracking figures or --tracks)")
      .OnOnly();
  // Written only when true: config.json before self-calibration had no key.
  t.AddOptional("self_calibrate", &O::self_calibrate,
                "Estimate the detector's noise model from the sequences (robust linking, residuals of the smoothed "
                "tracks, to a fixed point) and link and fit with it; writes OUT/detector_model.json "
                "(docs/detector_calibration.md)",
                false);
  t.AddOptional("detector_model", &O::detector_model_path,
                "A detector model JSON (samp calibrate-detector) giving the tracker's and the fit's detector sigmas "
                "(instead of --tracker-*-sigma and --self-calibrate)",
                std::string())
      .ExistingFile();
  // Written only when false: config.json before the plot had no key.
  t.AddOptional("detector_plot", &O::detector_plot,
                "Do not draw the run's detector model (self-calibrated or --detector-model) as "
                "OUT/detector_model.png beside detector_model.json (docs/detector_calibration.md, \"The plot\")",
                true)
      .OffOnly();
  return t;
}

}  // namespace

const OptionTable<RunFitOptions>& RunFitOptionTable() {
  static const OptionTable<RunFitOptions> table = MakeRunFitTable();
  return table;
}

}  // namespace samp
