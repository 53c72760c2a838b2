// The tracker's option table (data/tracker_option_table.h): Check() names the
// field, its rule and the value, every field is wired to its own member, the
// JSON round-trips, and docs/fitting.md's tracker option list is the table's
// (regenerate: `samp fit --help-options tracker-markdown`).
#include <gtest/gtest.h>

#include "libsamp/data/tracker_option_table.h"
#include "tests/testing/expect_error.h"
#include "tests/testing/option_table_checks.h"

namespace samp {
namespace {

TEST(TrackerOptionTable, CheckNamesTheFieldTheRuleAndTheValue) {
  EXPECT_NO_THROW(TrackerOptions().Check());
  TrackerOptions o;
  o.yaw_gate_deg = 120;
  test::ExpectError([&] { o.Check(); }, {"TrackerOptions.yaw_gate_deg must be in (0, 90], got 120"});
  o = TrackerOptions();
  o.along_sigma_c = -0.01;
  test::ExpectError([&] { o.Check(); }, {"TrackerOptions.along_sigma_c must be >= 0, got -0.01"});
}

TEST(TrackerOptionTable, EveryFieldIsWiredToItsOwnMember) {
  test::ExpectEveryFieldWired(TrackerOptionTable(), "tracker-");
  test::ExpectJsonRoundTrip(TrackerOptionTable());
}

TEST(TrackerOptionTable, CommandLineNamesKeepTheOldOnes) {
  std::map<std::string, OptionInfo> by_name;
  for (const OptionInfo& i : TrackerOptionTable().Describe()) by_name[i.name] = i;
  EXPECT_EQ(CommandLineName(by_name["min_track_length"].flag, "tracker-"), "--min-track-length");
  EXPECT_EQ(CommandLineName(by_name["frame_rate_hz"].flag, "tracker-"), "--frame-rate");
  EXPECT_EQ(CommandLineName(by_name["gate_chi2"].flag, "tracker-"), "--tracker-gate-chi2");
  EXPECT_EQ(CommandLineName(by_name["gate_chi2"].deprecated.at(0).first, "tracker-"), "--tracker-gate");
  EXPECT_EQ(OffFlagName(by_name["join_fragments"], "tracker-"), "--no-tracker-join-fragments");
  EXPECT_EQ(CommandLineName(by_name["join_fragments"].deprecated.at(1).first, "tracker-"), "--no-tracker-join");
}

TEST(TrackerOptionTable, DocsListTheTable) {
  EXPECT_EQ(test::DocSection(SAMP_FITTING_DOC, "samp fit --help-options tracker-markdown"),
            OptionsMarkdown(TrackerOptionTable().Describe(), "tracker-"))
      << "docs/fitting.md's tracker option list differs from the table: regenerate it with "
         "`samp fit --help-options tracker-markdown`";
}

}  // namespace
}  // namespace samp
