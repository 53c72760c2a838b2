// The option tables of training (model/pca_option_table.h,
// scan/scan_option_table.h, sdf/sdf_option_table.h): Check() names the field,
// its rule and the value, every field is wired to its own member, the JSON
// keeps the keys the model files store, and docs/training.md's lists are the
// tables' (regenerate: `samp train --help-options markdown`, `gate-markdown`).
#include <gtest/gtest.h>

#include "libsamp/model/pca_option_table.h"
#include "libsamp/model/train_option_table.h"
#include "libsamp/model/trainer.h"
#include "libsamp/scan/scan_option_table.h"
#include "libsamp/sdf/sdf_option_table.h"
#include "tests/testing/expect_error.h"
#include "tests/testing/option_table_checks.h"

namespace samp {
namespace {

std::vector<std::string> JsonKeys(const nlohmann::json& j) {
  std::vector<std::string> keys;
  for (auto it = j.begin(); it != j.end(); ++it) keys.push_back(it.key());
  return keys;
}

TEST(TrainOptionTables, CheckNamesTheFieldTheRuleAndTheValue) {
  EXPECT_NO_THROW(ScanOptions().Check());
  EXPECT_NO_THROW(SdfOptions().Check());
  EXPECT_NO_THROW(SdfQualityOptions().Check());
  EXPECT_NO_THROW(PcaOptions().Check());
  ScanOptions scan;
  scan.width = scan.height = 10000;
  test::ExpectError([&] { scan.Check(); }, {"ScanOptions.width must be at most 2^26 pixels with height, got 10000"});
  scan = ScanOptions();
  scan.distance_factor = 1;
  test::ExpectError([&] { scan.Check(); }, {"ScanOptions.distance_factor must be > 1, got 1"});
  SdfOptions sdf;
  sdf.closing_radius_voxels = 0;
  test::ExpectError([&] { sdf.Check(); }, {"SdfOptions.closing_radius_voxels must be in (0, 16], got 0"});
  SdfQualityOptions gate;
  gate.borderline_box_fill = 0.2;
  test::ExpectError([&] { gate.Check(); }, {"SdfQualityOptions.borderline_box_fill must be >= min_box_fill, got 0.2"});
  PcaOptions pca;
  pca.num_components = 0;
  test::ExpectError([&] { pca.Check(); }, {"PcaOptions.num_components must be >= 1, got 0"});
  TrainOptions train;
  train.cad_folder = "cars";
  train.output_path = "m.vdb";
  train.scan.num_views = 0;
  test::ExpectError([&] { train.Check(); }, {"ScanOptions.num_views must be >= 1, got 0"});
}

TEST(TrainOptionTables, EveryFieldIsWiredToItsOwnMember) {
  test::ExpectEveryFieldWired(ScanOptionTable(), "");
  test::ExpectJsonRoundTrip(ScanOptionTable());
  test::ExpectEveryFieldWired(SdfOptionTable(), "");
  test::ExpectJsonRoundTrip(SdfOptionTable());
  test::ExpectEveryFieldWired(SdfQualityOptionTable(), "gate-");
  test::ExpectJsonRoundTrip(SdfQualityOptionTable());
  test::ExpectEveryFieldWired(PcaOptionTable(), "");
  test::ExpectJsonRoundTrip(PcaOptionTable());
}

// The keys of samp_options in the model files written before the tables.
TEST(TrainOptionTables, JsonKeepsTheModelFilesKeys) {
  EXPECT_EQ(JsonKeys(OptionsToJson(ScanOptions())),
            (std::vector<std::string>{"distance_factor", "fov_deg", "height", "num_views", "width"}));
  EXPECT_EQ(JsonKeys(OptionsToJson(SdfOptions())),
            (std::vector<std::string>{"carve_margin", "closing_radius_voxels", "min_inside_fraction", "sign",
                                      "truncation"}));
  EXPECT_EQ(OptionsToJson(SdfOptions()).at("sign"), "carving_and_closing");
  EXPECT_EQ(JsonKeys(OptionsToJson(SdfQualityOptions())),
            (std::vector<std::string>{"borderline_box_fill", "borderline_closing_agreement",
                                      "borderline_largest_component", "min_box_fill", "min_closing_agreement",
                                      "min_largest_component"}));
  EXPECT_EQ(JsonKeys(OptionsToJson(PcaOptions())), (std::vector<std::string>{"num_components"}));
  // The trainer options round-trip through the model file's JSON.
  TrainOptions o;
  o.cad_folder = "cars";
  o.sdf.sign = SdfOptions::Sign::kCarving;
  o.gate.min_box_fill = 0.25;
  o.scan.num_views = 64;
  o.pca.num_components = 3;
  EXPECT_EQ(TrainOptionsFromJson(o.ToJson(), "test").ToJson(), o.ToJson());
}

// TrainOptions' own fields: the rules, the wiring, and the keys the model
// files store (output paths and threads are not stored).
TEST(TrainOptionTables, TrainOptionsRulesAndJson) {
  TrainOptions o;
  test::ExpectError([&] { o.Check(); }, {"TrainOptions.cad_folder must be given, got "});
  o.cad_folder = "cars";
  test::ExpectError([&] { o.Check(); }, {"TrainOptions.output_path must be given, got "});
  o.output_path = "m.vdb";
  EXPECT_NO_THROW(o.Check());
  o.preset = "kitti";
  test::ExpectError([&] { o.Check(); },
                    {"TrainOptions.preset must be empty or one of shapenet, apollocar3d, got kitti"});
  o.preset = "shapenet";
  o.size_variants = {Eigen::Vector3d(1.0, 1.1, 2.5)};
  test::ExpectError([&] { o.Check(); }, {"TrainOptions.size_variants must be in [0.5, 2], got 1,1.1,2.5"});
  o.size_variants.clear();
  o.num_threads = -2;
  test::ExpectError([&] { o.Check(); }, {"TrainOptions.num_threads must be >= 0, got -2"});

  test::ExpectEveryFieldWired(TrainOptionTable(), "", {"grid.", "scan.", "sdf.", "gate.", "pca."});
  test::ExpectJsonRoundTrip(TrainOptionTable());
  EXPECT_EQ(JsonKeys(OptionsToJson(TrainOptions())),
            (std::vector<std::string>{"cad_folder", "gate", "grid", "manifest", "pca", "preset", "scan", "sdf",
                                      "size_variants"}));
  // The computed fields set what they stand for.
  TrainOptions c;
  for (const OptionBinding& b : TrainOptionTable().Bind(&c)) {
    if (b.info.name == "voxel_size") b.set("0.05");
    if (b.info.name == "resolution") b.set("128");
    if (b.info.name == "size_variants") b.set_list({"1", "1.1", "1.2", "0.9", "1", "1"});
  }
  EXPECT_EQ(c.grid.dims, GridSpec::CarDefault(0.05).dims);
  // The grid's edges keep the voxel size, the voxel size keeps the edges, in either order.
  for (const bool voxel_first : {true, false}) {
    TrainOptions g;
    std::vector<OptionBinding> bindings = TrainOptionTable().Bind(&g);
    auto set = [&](const std::string& name, const std::string& value) {
      for (const OptionBinding& b : bindings)
        if (b.info.name == name) b.set(value);
    };
    if (voxel_first) set("voxel_size", "0.05");
    set("grid_length", "6.8");
    set("grid_height", "3.1");
    set("grid_width", "3.2");
    if (!voxel_first) set("voxel_size", "0.05");
    EXPECT_EQ(g.grid, GridSpec::Car(6.8, 3.1, 3.2, 0.05)) << voxel_first;
    EXPECT_EQ(g.grid.Size(), Eigen::Vector3d(6.8, 3.1, 3.2));
    // The model file records the grid itself (no extra keys).
    EXPECT_EQ(TrainOptionsFromJson(g.ToJson(), "big.vdb").grid, g.grid);
  }
  EXPECT_EQ(TrainOptions().grid, GridSpec::CarDefault());
  EXPECT_EQ(c.scan.width, 128);
  EXPECT_EQ(c.scan.height, 128);
  ASSERT_EQ(c.size_variants.size(), 2u);
  EXPECT_EQ(c.size_variants[1], Eigen::Vector3d(0.9, 1, 1));
  // A model file written before size variants existed has none.
  nlohmann::json old = OptionsToJson(c);
  old.erase("size_variants");
  EXPECT_TRUE(TrainOptionsFromJson(DumpJson(old), "old.vdb").size_variants.empty());
  EXPECT_EQ(TrainOptionsFromJson(c.ToJson(), "new.vdb").ToJson(), c.ToJson());
}

TEST(TrainOptionTables, DocsListTheTables) {
  std::vector<OptionInfo> infos;
  for (const std::vector<OptionInfo>& part :
       {PcaOptionTable().Describe(), ScanOptionTable().Describe(), SdfOptionTable().Describe()}) {
    infos.insert(infos.end(), part.begin(), part.end());
  }
  EXPECT_EQ(test::DocSection(SAMP_TRAINING_DOC, "samp train --help-options markdown"), OptionsMarkdown(infos))
      << "docs/training.md's option list differs from the tables: regenerate it with "
         "`samp train --help-options markdown`";
  EXPECT_EQ(test::DocSection(SAMP_TRAINING_DOC, "samp train --help-options gate-markdown"),
            OptionsMarkdown(SdfQualityOptionTable().Describe(), "gate-"))
      << "docs/training.md's gate option list differs from the table: regenerate it with "
         "`samp train --help-options gate-markdown`";
  EXPECT_EQ(test::DocSection(SAMP_TRAINING_DOC, "samp train --help-options run-markdown"),
            OptionsMarkdown(TrainOptionTable().Describe()))
      << "docs/training.md's run option list differs from the table: regenerate it with "
         "`samp train --help-options run-markdown`";
}

}  // namespace
}  // namespace samp
