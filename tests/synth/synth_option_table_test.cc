// The option tables of the scene generator (synth/synth_option_table.h):
// Check() names the field, its rule and the value, every field is wired to
// its own member (JSON and command line), the JSON round-trips and keeps the
// bytes of the files written before the tables, and the option list of
// docs/synthetic.md is the table's (regenerate: `samp synth --help-options markdown`).
#include <gtest/gtest.h>

#include <cmath>

#include "libsamp/synth/synth_option_table.h"
#include "tests/testing/expect_error.h"
#include "tests/testing/option_table_checks.h"

namespace samp {
namespace {

SynthOptions Named() {
  SynthOptions o;
  o.output_folder = "out";
  return o;
}

TEST(SynthOptionTable, CheckNamesTheFieldTheRuleAndTheValue) {
  EXPECT_NO_THROW(Named().Check());
  EXPECT_NO_THROW([] {
    SynthOptions o = SynthOptions::Clean();
    o.output_folder = "out";
    o.Check();
  }());
  SynthOptions o = Named();
  o.num_frames = 1001;
  test::ExpectError([&] { o.Check(); }, {"SynthOptions.num_frames must be in [1, 1000], got 1001"});
  o = Named();
  o.max_distance = 4.5;
  o.min_distance = 5.0;
  test::ExpectError([&] { o.Check(); }, {"SynthOptions.max_distance must be > min_distance, got 4.5"});
  o = Named();
  o.standing_share = 0.8;
  o.turning_share = 0.3;
  test::ExpectError([&] { o.Check(); }, {"SynthOptions.turning_share must be <= 1 - standing_share, got 0.3"});
  o = Named();
  o.layout = SynthLayout::kKittiTracking;
  o.first_sequence = 9999;
  o.num_sequences = 2;
  test::ExpectError([&] { o.Check(); }, {"SynthOptions.first_sequence must be", "KITTI tracking's layout"});
  o = Named();
  o.street.kerb_height = 0.5;
  test::ExpectError([&] { o.Check(); }, {"SynthOptions.street.kerb_height must be in [0, 0.3], got 0.5"});
  test::ExpectError([&] { o.street.Check(); }, {"StreetOptions.kerb_height must be in [0, 0.3], got 0.5"});
  o = Named();
  o.detector.flip_probability = 0.5;
  o.detector.flip_mean_run_frames = 0.5;
  test::ExpectError([&] { o.detector.Check(); },
                    {"DetectorModelOptions.flip_mean_run_frames must be 0 (independent) or >= max(1, p / (1 - p))"});
  o = Named();
  o.detector.width_bias = std::nan("");
  test::ExpectError([&] { o.Check(); }, {"SynthOptions.detector.width_bias must be finite, got nan"});
  o = Named();
  o.output_folder.clear();
  test::ExpectError([&] { o.Check(); }, {"output_folder is empty"});
}

TEST(SynthOptionTable, EveryFieldIsWiredToItsOwnMember) {
  test::ExpectEveryFieldWired(SynthOptionTable(), "");
  test::ExpectEveryFieldWired(StreetOptionTable(), "");
  test::ExpectEveryFieldWired(DetectorModelOptionTable(), "det-");
}

TEST(SynthOptionTable, JsonRoundTripsEveryField) {
  test::ExpectJsonRoundTrip(SynthOptionTable());
  nlohmann::json missing = OptionsToJson(SynthOptions());
  missing["street"].erase("kerb_height");
  SynthOptions read;
  test::ExpectError([&] { OptionsFromJson(JsonFields(missing, "config.json"), &read); },
                    {"config.json", "street", "kerb_height"});
}

// The keys and values of the config.json that samp synth wrote before the
// table: every field, the detector's profile and biases and the layout only
// when set, the disparity source by the names "sgbm" and "true+noise".
TEST(SynthOptionTable, JsonKeepsTheFormerKeysAndNames) {
  SynthOptions o;
  o.seed = 18446744073709551615ull;
  nlohmann::json j = ParseJson(o.ToJson(), "ToJson");
  EXPECT_EQ(j.size(), 50u);
  EXPECT_EQ(j["street"].size(), 14u);
  EXPECT_EQ(j["detector"].size(), 19u);
  EXPECT_EQ(j["seed"].get<uint64_t>(), 18446744073709551615ull);
  EXPECT_EQ(j["disparity"], "sgbm");
  EXPECT_EQ(j["scene"], "street");
  EXPECT_FALSE(j.contains("layout"));
  EXPECT_FALSE(j.contains("output_folder"));
  EXPECT_FALSE(j["detector"].contains("profile"));
  EXPECT_FALSE(j["detector"].contains("width_bias"));
  o.disparity = DisparitySource::kTrueWithNoise;
  o.layout = SynthLayout::kKittiTracking;
  o.detector = DetectorProfile("kitti-boxes");
  j = ParseJson(o.ToJson(), "ToJson");
  EXPECT_EQ(j["disparity"], "true+noise");
  EXPECT_EQ(j["layout"], "kitti-tracking");
  EXPECT_EQ(j["detector"]["profile"], "kitti-boxes");
  EXPECT_TRUE(j["detector"].contains("width_bias"));
  EXPECT_EQ(SynthOptions::Clean().ToJson().find("\"scene\": \"clean\"") != std::string::npos, true);
}

TEST(SynthOptionTable, CommandLineNamesAreTheFormerOnes) {
  std::map<std::string, OptionInfo> by_name;
  for (const OptionInfo& i : SynthOptionTable().Describe()) by_name[i.name] = i;
  EXPECT_EQ(CommandLineName(by_name["num_sequences"].flag, ""), "--sequences");
  EXPECT_EQ(CommandLineName(by_name["num_frames"].flag, ""), "--frames");
  EXPECT_EQ(CommandLineName(by_name["parked_cars_per_sequence"].flag, ""), "--parked-cars");
  EXPECT_EQ(OffFlagName(by_name["shadows"], ""), "--no-shadows");
  EXPECT_EQ(CommandLineName(by_name["street.kerb_height"].flag, ""), "--kerb-height");
  EXPECT_EQ(CommandLineName(by_name["detector.flip_probability"].flag, ""), "--det-flip");
  EXPECT_EQ(CommandLineName(by_name["detector.yaw_sigma_deg_a"].flag, ""), "--det-yaw-sigma-a");
  EXPECT_EQ(by_name["disparity"].Validate("true"), "");
  EXPECT_NE(by_name["num_frames"].Validate("0").find("must be in [1, 1000]"), std::string::npos);
  EXPECT_TRUE(by_name["scene"].internal);
  EXPECT_TRUE(by_name["detector.profile"].internal);
}

TEST(SynthOptionTable, DocsListTheTable) {
  EXPECT_EQ(test::DocSection(SAMP_SYNTHETIC_DOC, "samp synth --help-options markdown"),
            OptionsMarkdown(SynthOptionTable().Describe()))
      << "docs/synthetic.md's option list differs from the table: regenerate it with "
         "`samp synth --help-options markdown`";
}

}  // namespace
}  // namespace samp
