// The option tables of training (model/pca_option_table.h,
// scan/scan_option_table.h, sdf/sdf_option_table.h): Check() names the field,
// its rule and the value, every field is wired to its own member, the JSON
// keeps the keys the model files store, and docs/training.md's lists are the
// tables' (regenerate: `samp train --help-options markdown`, `gate-markdown`).
#include <gtest/gtest.h>

#include "libsamp/model/pca_option_table.h"
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
}

}  // namespace
}  // namespace samp
