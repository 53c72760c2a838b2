// The candidate points' option table (data/observation_option_table.h):
// Check() names the field, its rule and the value, every field is wired to its
// own member, the JSON round-trips with config.json's former keys, and
// docs/fitting.md's list is the table's (regenerate:
// `samp fit --help-options observation-markdown`).
#include <gtest/gtest.h>

#include <cmath>

#include "libsamp/data/observation_option_table.h"
#include "tests/testing/expect_error.h"
#include "tests/testing/option_table_checks.h"

namespace samp {
namespace {

TEST(ObservationOptionTable, CheckNamesTheFieldTheRuleAndTheValue) {
  EXPECT_NO_THROW(ObservationOptions().Check());
  ObservationOptions o;
  o.box_margin = 3;
  test::ExpectError([&] { o.Check(); }, {"ObservationOptions.box_margin must be in [0, 2], got 3"});
  o = ObservationOptions();
  o.min_height_above_road = std::nan("");
  test::ExpectError([&] { o.Check(); }, {"ObservationOptions.min_height_above_road must be finite, got nan"});
  o = ObservationOptions();
  o.sigma_disparity_px = 0;
  test::ExpectError([&] { o.Check(); }, {"ObservationOptions.sigma_disparity_px must be > 0, got 0"});
}

TEST(ObservationOptionTable, EveryFieldIsWiredToItsOwnMember) {
  test::ExpectEveryFieldWired(ObservationOptionTable(), "");
  test::ExpectJsonRoundTrip(ObservationOptionTable());
}

TEST(ObservationOptionTable, JsonAndCommandLineKeepTheFormerNames) {
  const nlohmann::json j = OptionsToJson(ObservationOptions());
  std::vector<std::string> keys;
  for (auto it = j.begin(); it != j.end(); ++it) keys.push_back(it.key());
  EXPECT_EQ(keys, (std::vector<std::string>{"box_margin", "depth_gate_sigmas", "max_distance_to_detection",
                                            "max_points_per_frame", "min_disparity_px", "min_height_above_road",
                                            "nearest_box_claims", "seed", "sigma_disparity_px"}));
  std::map<std::string, OptionInfo> by_name;
  for (const OptionInfo& i : ObservationOptionTable().Describe()) by_name[i.name] = i;
  EXPECT_EQ(CommandLineName(by_name["sigma_disparity_px"].flag, ""), "--sigma-disparity");
  EXPECT_EQ(CommandLineName(by_name["max_points_per_frame"].flag, ""), "--max-points");
  EXPECT_EQ(OffFlagName(by_name["nearest_box_claims"], ""), "--shared-points");
  EXPECT_TRUE(by_name["seed"].internal);
}

TEST(ObservationOptionTable, DocsListTheTable) {
  EXPECT_EQ(test::DocSection(SAMP_FITTING_DOC, "samp fit --help-options observation-markdown"),
            OptionsMarkdown(ObservationOptionTable().Describe()))
      << "docs/fitting.md's candidate-point option list differs from the table: regenerate it with "
         "`samp fit --help-options observation-markdown`";
}

}  // namespace
}  // namespace samp
