#include "libsamp/sdf/sdf_option_table.h"

#include "libsamp/core/error.h"

namespace samp {

namespace {

OptionTable<SdfOptions> MakeSdfTable() {
  using O = SdfOptions;
  OptionTable<O> t("SdfOptions");
  t.Add("truncation", &O::truncation, "distances are clamped to +-truncation, m (0 = none)").NonNegative();
  t.Add("carve_margin", &O::carve_margin,
        "a voxel seen in front of the surface by less than this is not carved, m")
      .NonNegative();
  t.Add("min_inside_fraction", &O::min_inside_fraction,
        "a model whose SDF has a smaller inside (negative) share of the grid is rejected")
      .Flag("min-inside")
      .AtLeast(0)
      .AtMost(1);
  t.AddChoice("sign", &O::sign, SdfSignName, ParseSdfSign, {"carving", "carving_and_closing"},
              "how the sign is decided: carving alone, or also inside where the closing says inside "
              "(docs/sdf.md)");
  t.Add("closing_radius_voxels", &O::closing_radius_voxels,
        "closing radius tau, voxels: gaps narrower than about 2 tau are closed")
      .Flag("closing-radius")
      .Positive()
      .AtMost(16);
  return t;
}

// A minimum and its borderline limit, both shares in [0, 1], minimum first.
void AddLimits(OptionTable<SdfQualityOptions>* t, const char* min_name, double SdfQualityOptions::*min,
               const char* borderline_name, double SdfQualityOptions::*borderline, const std::string& figure) {
  t->Add(min_name, min, "a model whose " + figure + " is below this is rejected").AtLeast(0).AtMost(1);
  t->Add(borderline_name, borderline, "... below this it is kept and reported as borderline")
      .AtLeast(0)
      .AtMost(1)
      .Rule(std::string(">= ") + min_name,
            [min, borderline](const SdfQualityOptions& o) { return o.*borderline >= o.*min; });
}

OptionTable<SdfQualityOptions> MakeSdfQualityTable() {
  using O = SdfQualityOptions;
  OptionTable<O> t("SdfQualityOptions");
  AddLimits(&t, "min_box_fill", &O::min_box_fill, "borderline_box_fill", &O::borderline_box_fill,
            "inside volume over its bounding box's volume");
  AddLimits(&t, "min_largest_component", &O::min_largest_component, "borderline_largest_component",
            &O::borderline_largest_component, "share of the inside in its largest connected component");
  AddLimits(&t, "min_closing_agreement", &O::min_closing_agreement, "borderline_closing_agreement",
            &O::borderline_closing_agreement, "share of the inside the closing alone also calls inside");
  return t;
}

}  // namespace

const char* SdfSignName(SdfOptions::Sign sign) {
  return sign == SdfOptions::Sign::kCarving ? "carving" : "carving_and_closing";
}

SdfOptions::Sign ParseSdfSign(const std::string& name) {
  SAMP_CHECK(name == "carving" || name == "carving_and_closing")
      << "must be \"carving\" or \"carving_and_closing\", got \"" << name << "\"";
  return name == "carving" ? SdfOptions::Sign::kCarving : SdfOptions::Sign::kCarvingAndClosing;
}

const OptionTable<SdfOptions>& SdfOptionTable() {
  static const OptionTable<SdfOptions> table = MakeSdfTable();
  return table;
}

const OptionTable<SdfQualityOptions>& SdfQualityOptionTable() {
  static const OptionTable<SdfQualityOptions> table = MakeSdfQualityTable();
  return table;
}

void OptionFields(OptionsJson& io, SdfOptions& o) { SdfOptionTable().Json(io, o); }
void OptionFields(OptionsJson& io, SdfQualityOptions& o) { SdfQualityOptionTable().Json(io, o); }

}  // namespace samp
