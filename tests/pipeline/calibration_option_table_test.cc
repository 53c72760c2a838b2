// The option tables of the detector's noise model estimation
// (data/calibration_option_table.h): Check() names the field, its rule and the
// value, every field is wired to its own member, config.json records them only
// when they differ from the defaults, and docs/detector_calibration.md's list
// is the table's (regenerate: `samp fit --help-options calibration-markdown`).
#include <gtest/gtest.h>

#include "libsamp/data/calibration_option_table.h"
#include "libsamp/pipeline/fit_config.h"
#include "tests/testing/expect_error.h"
#include "tests/testing/option_table_checks.h"

namespace samp {
namespace {

TEST(CalibrationOptionTable, CheckNamesTheFieldTheRuleAndTheValue) {
  EXPECT_NO_THROW(CalibrationOptions().Check());
  CalibrationOptions o;
  o.noise.smoother_degree = 3;
  test::ExpectError([&] { o.Check(); }, {"CalibrationOptions.noise.smoother_degree must be in [1, 2], got 3"});
  o = CalibrationOptions();
  o.box.max_end_view_deg = 91;
  test::ExpectError([&] { o.Check(); }, {"CalibrationOptions.box.max_end_view_deg must be in [0, 90], got 91"});
  o = CalibrationOptions();
  o.tracker_sigma_scale = 0.5;
  test::ExpectError([&] { o.Check(); }, {"CalibrationOptions.tracker_sigma_scale must be >= 1, got 0.5"});
  o = CalibrationOptions();
  o.noise.bin_edges = {0, 20, 10};
  test::ExpectError([&] { o.Check(); },
                    {"CalibrationOptions.noise.bin_edges must be a non-empty increasing list, got 0,20,10"});
  DetectorNoiseOptions noise;
  noise.trim_sigmas = 1;
  test::ExpectError([&] { noise.Check(); }, {"DetectorNoiseOptions.trim_sigmas must be >= 1.5, got 1"});
  BoxConventionOptions box;
  box.min_cars = 0;
  test::ExpectError([&] { box.Check(); }, {"BoxConventionOptions.min_cars must be >= 1, got 0"});
}

TEST(CalibrationOptionTable, EveryFieldIsWiredToItsOwnMember) {
  test::ExpectEveryFieldWired(BoxConventionOptionTable(), "box-");
  test::ExpectJsonRoundTrip(BoxConventionOptionTable());
  // The noise options' JSON also holds the bin edges, which the table does not list.
  CalibrationOptions o;
  for (const OptionBinding& b : CalibrationOptionTable().Bind(&o)) b.set(test::OtherValue(b.info));
  o.noise.bin_edges = {0, 15, 30};
  const nlohmann::json written = OptionsToJson(o);
  CalibrationOptions read;
  OptionsFromJson(JsonFields(written, "config.json"), &read);
  EXPECT_EQ(OptionsToJson(read), written);
  EXPECT_EQ(read.noise.bin_edges, o.noise.bin_edges);
  EXPECT_EQ(read.box.min_cars, o.box.min_cars);
  EXPECT_NE(read.box.min_cars, BoxConventionOptions().min_cars);
}

TEST(CalibrationOptionTable, ConfigJsonRecordsThemOnlyWhenChanged) {
  RunFitOptions run;
  EXPECT_FALSE(OptionsToJson(run).contains("calibration"));
  run.calibration.max_iterations = 7;
  run.calibration.noise.bin_edges = {0, 25};
  const nlohmann::json j = OptionsToJson(run);
  ASSERT_TRUE(j.contains("calibration"));
  EXPECT_EQ(j.at("calibration").at("max_iterations"), 7);
  RunFitOptions read;
  OptionsFromJson(JsonFields(j, "config.json"), &read);
  EXPECT_EQ(read.calibration.max_iterations, 7);
  EXPECT_EQ(read.calibration.noise.bin_edges, (std::vector<double>{0, 25}));
  // A config.json without the key reads the defaults.
  nlohmann::json without = j;
  without.erase("calibration");
  OptionsFromJson(JsonFields(without, "config.json"), &read);
  EXPECT_EQ(read.calibration.max_iterations, CalibrationOptions().max_iterations);
}

TEST(CalibrationOptionTable, DocsListTheTable) {
  EXPECT_EQ(test::DocSection(SAMP_CALIBRATION_DOC, "samp fit --help-options calibration-markdown"),
            OptionsMarkdown(CalibrationOptionTable().Describe(), "calibration-"))
      << "docs/detector_calibration.md's option list differs from the table: regenerate it with "
         "`samp fit --help-options calibration-markdown`";
}

}  // namespace
}  // namespace samp
