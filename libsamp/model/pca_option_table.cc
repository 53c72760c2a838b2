#include "libsamp/model/pca_option_table.h"

namespace samp {

namespace {

OptionTable<PcaOptions> MakePcaTable() {
  OptionTable<PcaOptions> t("PcaOptions");
  t.Add("num_components", &PcaOptions::num_components,
        "principal components R kept (needs at least R + 1 usable models)")
      .Flag("components")
      .Short('R')
      .AtLeast(1);
  return t;
}

}  // namespace

const OptionTable<PcaOptions>& PcaOptionTable() {
  static const OptionTable<PcaOptions> table = MakePcaTable();
  return table;
}

void OptionFields(OptionsJson& io, PcaOptions& o) { PcaOptionTable().Json(io, o); }

}  // namespace samp
