#include "libsamp/scan/scan_option_table.h"

#include <cstdint>

namespace samp {

namespace {

OptionTable<ScanOptions> MakeScanTable() {
  using O = ScanOptions;
  OptionTable<O> t("ScanOptions");
  t.Add("num_views", &O::num_views, "scan viewpoints per model (Fibonacci sphere)").Flag("views").AtLeast(1);
  t.Add("width", &O::width, "width of each view, px (samp train: --resolution sets width and height)")
      .Internal()
      .AtLeast(1)
      .Rule("at most 2^26 pixels with height",
            [](const O& o) { return std::int64_t(o.width) * o.height <= (std::int64_t(1) << 26); });
  t.Add("height", &O::height, "height of each view, px").Internal().AtLeast(1);
  t.Add("fov_deg", &O::fov_deg, "field of view of each (square) view, deg").Flag("scan-fov").Positive().Below(180);
  t.Add("distance_factor", &O::distance_factor,
        "camera distance to the mesh's box centre in bounding-sphere radii (cameras outside the sphere)")
      .Flag("scan-distance")
      .Above(1);
  return t;
}

}  // namespace

const OptionTable<ScanOptions>& ScanOptionTable() {
  static const OptionTable<ScanOptions> table = MakeScanTable();
  return table;
}

void OptionFields(OptionsJson& io, ScanOptions& o) { ScanOptionTable().Json(io, o); }

}  // namespace samp
