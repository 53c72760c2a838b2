// The option tables of drawing a fit (viz/view_option_table.h): Check() names
// the field, its rule and the value, `samp view`'s options set their own
// members, and docs/fitting.md's list is the table's (regenerate:
// `samp view --help-options markdown`).
#include <gtest/gtest.h>

#include "libsamp/viz/view_option_table.h"
#include "tests/testing/expect_error.h"
#include "tests/testing/option_table_checks.h"

namespace samp {
namespace {

TEST(ViewOptionTables, CheckNamesTheFieldTheRuleAndTheValue) {
  FitVisualsOptions o;
  test::ExpectError([&] { o.Check(); }, {"FitVisualsOptions.output_dir must be given, got "});
  o.output_dir = "out";
  EXPECT_NO_THROW(o.Check());
  o.pictures = o.html = false;
  test::ExpectError([&] { o.Check(); }, {"FitVisualsOptions.html must be true when pictures is false, got false"});
  o.html = true;
  o.load.error_tau = 0;
  test::ExpectError([&] { o.Check(); }, {"FitVisualsOptions.load.error_tau must be > 0, got 0"});
  test::ExpectError([&] { o.load.Check(); }, {"LoadFitRunOptions.error_tau must be > 0, got 0"});
  FitHtmlOptions page;
  page.max_points_per_frame = -1;
  test::ExpectError([&] { page.Check(); }, {"FitHtmlOptions.max_points_per_frame must be >= 0, got -1"});
}

// Each command-line option sets its own member (and no other field's text).
TEST(ViewOptionTables, EveryOptionSetsItsOwnMember) {
  for (const OptionInfo& info : FitVisualsOptionTable().Describe()) {
    FitVisualsOptions o;
    std::map<std::string, std::string> before, after;
    for (const OptionBinding& b : FitVisualsOptionTable().Bind(&o)) before[b.info.name] = b.info.default_text;
    for (const OptionBinding& b : FitVisualsOptionTable().Bind(&o)) {
      if (b.info.name == info.name) b.set(test::OtherValue(info));
    }
    for (const OptionBinding& b : FitVisualsOptionTable().Bind(&o)) after[b.info.name] = b.info.default_text;
    for (const auto& [name, text] : before) {
      EXPECT_EQ(after[name] != text, name == info.name) << info.name << ": " << name;
    }
  }
}

TEST(ViewOptionTables, DocsListTheTable) {
  EXPECT_EQ(test::DocSection(SAMP_FITTING_DOC, "samp view --help-options markdown"),
            OptionsMarkdown(FitVisualsOptionTable().Describe()))
      << "docs/fitting.md's viewer option list differs from the table: regenerate it with "
         "`samp view --help-options markdown`";
}

}  // namespace
}  // namespace samp
