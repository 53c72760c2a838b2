// The option tables of the fitter (fit/fit_option_table.h): Check() names the
// field, its rule and the value, every field is wired to its own member (JSON
// and command line), the JSON round-trips, and the option list of
// docs/fitting.md is the table's (regenerate: `samp fit --help-options markdown`).
#include <gtest/gtest.h>

#include <cmath>

#include "libsamp/fit/fit_option_table.h"
#include "tests/testing/expect_error.h"
#include "tests/testing/option_table_checks.h"

namespace samp {
namespace {

TEST(FitOptionTable, CheckNamesTheFieldTheRuleAndTheValue) {
  EXPECT_NO_THROW(FitOptions().Check());
  FitOptions o;
  o.em_iterations = -1;
  test::ExpectError([&] { o.Check(); }, {"FitOptions.em_iterations must be >= 0, got -1"});
  o = FitOptions();
  o.association_radius = std::nan("");
  test::ExpectError([&] { o.Check(); }, {"FitOptions.association_radius must be > 0, got nan"});
  o = FitOptions();
  o.max_motion_off_axis = 2.0;
  test::ExpectError([&] { o.Check(); }, {"FitOptions.max_motion_off_axis must be in (0, 1.5708], got 2"});
  o = FitOptions();
  o.max_solve_points_per_frame = 5;  // below min_points_per_frame = 10
  test::ExpectError([&] { o.Check(); },
                    {"FitOptions.max_solve_points_per_frame must be 0 (all) or >= min_points_per_frame, got 5"});
  o.max_solve_points_per_frame = 0;
  EXPECT_NO_THROW(o.Check());
  o = FitOptions();
  o.linear_solver = "dense_normal_cholesky";
  test::ExpectError([&] { o.Check(); }, {"FitOptions.linear_solver must be one of sparse_normal_cholesky,",
                                         "got dense_normal_cholesky"});
  o = FitOptions();
  o.motion_noise.sigma_yaw = 0.0;
  test::ExpectError([&] { o.Check(); }, {"FitOptions.motion_noise.sigma_yaw must be > 0, got 0"});
  test::ExpectError([&] { o.motion_noise.Check(); }, {"MotionNoise.sigma_yaw must be > 0, got 0"});
}

TEST(FitOptionTable, EveryFieldIsWiredToItsOwnMember) {
  test::ExpectEveryFieldWired(FitOptionTable(), "");
  test::ExpectEveryFieldWired(MotionNoiseOptionTable(), "motion-");
}

TEST(FitOptionTable, JsonRoundTripsEveryField) {
  test::ExpectJsonRoundTrip(FitOptionTable());
  nlohmann::json missing = OptionsToJson(FitOptions());
  missing["motion_noise"].erase("sigma_yaw");
  FitOptions read;
  test::ExpectError([&] { OptionsFromJson(JsonFields(missing, "config.json"), &read); },
                    {"config.json", "motion_noise", "sigma_yaw"});
}

TEST(FitOptionTable, CommandLineValuesAreCheckedByTheRule) {
  std::map<std::string, OptionInfo> by_name;
  for (const OptionInfo& i : FitOptionTable().Describe()) by_name[i.name] = i;
  EXPECT_EQ(by_name["em_iterations"].Validate("-1"), "must be >= 0, got -1");
  EXPECT_NE(by_name["em_iterations"].Validate("1.5").find("not an integer"), std::string::npos);
  EXPECT_EQ(by_name["em_iterations"].Validate("3"), "");
  EXPECT_NE(by_name["huber_threshold"].Validate("0").find("must be > 0"), std::string::npos);
  EXPECT_NE(by_name["data_term"].Validate("sdf").find("one of ray-depth, paper, disparity"), std::string::npos);
  EXPECT_EQ(by_name["data_term"].Validate("paper"), "");
  // Names: the field's, the old one kept as deprecated; nested with a prefix.
  EXPECT_EQ(CommandLineName(by_name["huber_threshold"].flag, ""), "--huber-threshold");
  ASSERT_EQ(by_name["huber_threshold"].deprecated.size(), 1u);
  EXPECT_EQ(by_name["huber_threshold"].deprecated[0].first, "huber");
  EXPECT_EQ(OffFlagName(by_name["mixture_loss"], ""), "--huber-loss");
  EXPECT_EQ(OffFlagName(by_name["detection_position"], ""), "--no-detection-position");
  EXPECT_EQ(CommandLineName(by_name["motion_noise.sigma_yaw"].flag, ""), "--motion-sigma-yaw");
  EXPECT_TRUE(by_name["keep_points"].internal);
}

TEST(FitOptionTable, DocsListTheTable) {
  EXPECT_EQ(test::DocSection(SAMP_FITTING_DOC, "samp fit --help-options markdown"),
            OptionsMarkdown(FitOptionTable().Describe()))
      << "docs/fitting.md's option list differs from the table: regenerate it with "
         "`samp fit --help-options markdown`";
}

}  // namespace
}  // namespace samp
