#include "libsamp/viz/view_option_table.h"

namespace samp {

namespace {

OptionTable<LoadFitRunOptions> MakeLoadFitRunTable() {
  using O = LoadFitRunOptions;
  OptionTable<O> t("LoadFitRunOptions");
  t.Add("read_images", &O::read_images, "list the left images (for the overlays)").Internal();
  t.Add("read_ground_truth", &O::read_ground_truth, "read SEQ/gt when present: true boxes, error colouring")
      .Internal();
  t.Add("error_tau", &O::error_tau, "Error colouring threshold tau, m").Flag("tau").Positive();
  t.Add("error_samples", &O::error_samples, "ground-truth surface samples for the errors").Internal().Positive();
  return t;
}

OptionTable<FitHtmlOptions> MakeFitHtmlTable() {
  using O = FitHtmlOptions;
  OptionTable<O> t("FitHtmlOptions");
  t.Add("title", &O::title, "page title (empty: \"samp fit: <output_dir>\")").Internal();
  t.Add("max_points_per_frame", &O::max_points_per_frame,
        "At most this many points per track and frame in the page (0 = all)")
      .Flag("max-points")
      .NonNegative();
  return t;
}

OptionTable<FitVisualsOptions> MakeFitVisualsTable() {
  using O = FitVisualsOptions;
  OptionTable<O> t("FitVisualsOptions");
  // The help is samp view's.
  t.Add("output_dir", &O::output_dir, "A samp fit output folder, or a model file")
      .Positional("OUT")
      .Required()
      .ExistingPath();
  t.Add("html_path", &O::html_path, "The page to write (default: OUT/index.html for a fit)").Short('o').Flag("html");
  t.Add("pictures", &O::pictures, "Also write the PNG pictures of a fit (OUT/pictures/; samp view: off unless given)")
      .OnOnly();
  t.Add("html", &O::html, "the viewer page into html_path (samp fit --html)")
      .Internal()
      .Rule("true when pictures is false", [](const O& o) { return o.pictures || o.html; });
  t.Add("only_error_surfaces", &O::only_error_surfaces, "pictures: only track_<id>_error.png (samp eval --pictures)")
      .Internal();
  t.Add("pictures_folder", &O::pictures_folder, "where the pictures go (empty: OUT/pictures)").Internal();
  t.AddNested("load", &O::load, LoadFitRunOptionTable(), "");
  t.AddNested("page", &O::page, FitHtmlOptionTable(), "");
  return t;
}

}  // namespace

const OptionTable<LoadFitRunOptions>& LoadFitRunOptionTable() {
  static const OptionTable<LoadFitRunOptions> table = MakeLoadFitRunTable();
  return table;
}

const OptionTable<FitHtmlOptions>& FitHtmlOptionTable() {
  static const OptionTable<FitHtmlOptions> table = MakeFitHtmlTable();
  return table;
}

const OptionTable<FitVisualsOptions>& FitVisualsOptionTable() {
  static const OptionTable<FitVisualsOptions> table = MakeFitVisualsTable();
  return table;
}

}  // namespace samp
