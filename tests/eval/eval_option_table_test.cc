// The option table of the evaluation (eval/eval_option_table.h): Check()
// names the field, its rule and the value, the JSON (results.json's
// "options") keeps its keys and round-trips, and docs/evaluation.md's list is
// the table's (regenerate: `samp eval --help-options markdown`).
#include <gtest/gtest.h>

#include "libsamp/eval/eval_option_table.h"
#include "tests/testing/expect_error.h"
#include "tests/testing/option_table_checks.h"

namespace samp {
namespace {

EvalOptions Named() {
  EvalOptions o;
  o.sequences = {"seq"};
  o.output_folder = "out";
  return o;
}

TEST(EvalOptionTable, CheckNamesTheFieldTheRuleAndTheValue) {
  EXPECT_NO_THROW(Named().Check());
  EvalOptions o = Named();
  o.headline_tau = 0.22;
  test::ExpectError([&] { o.Check(); }, {"EvalOptions.headline_tau must be one of the taus, got 0.22"});
  o = Named();
  o.min_iou = 1.5;
  test::ExpectError([&] { o.Check(); }, {"EvalOptions.min_iou must be in (0, 1], got 1.5"});
  o = Named();
  o.max_truncation = -0.1;
  test::ExpectError([&] { o.Check(); }, {"EvalOptions.max_truncation must be in [0, 1], got -0.1"});
  o = Named();
  o.taus = {0.2, 0.1};
  test::ExpectError([&] { o.Check(); }, {"eval: taus must be increasing"});
  o = Named();
  o.sequences.clear();
  test::ExpectError([&] { o.Check(); }, {"eval: no sequence given"});
}

TEST(EvalOptionTable, JsonKeepsItsKeysAndRoundTrips) {
  EvalOptions o = Named();
  std::vector<std::string> keys;
  const nlohmann::json j = OptionsToJson(o);
  for (auto it = j.begin(); it != j.end(); ++it) keys.push_back(it.key());
  EXPECT_EQ(keys, (std::vector<std::string>{"detection_baseline", "detections_path", "distance_window",
                                            "headline_tau", "max_occlusion", "max_truncation", "min_box_height_px",
                                            "min_iou", "min_segment_pixels", "num_threads", "per_frame_distance",
                                            "results", "sequences", "stereo_baseline", "taus"}));
  for (const OptionBinding& b : EvalOptionTable().Bind(&o)) b.set(test::OtherValue(b.info));
  o.results = {{"full", "fit_full"}, {"single", "fit_single"}};
  o.taus = {0.1, 0.3};
  const nlohmann::json written = OptionsToJson(o);
  EXPECT_EQ(written.at("results"), nlohmann::json::parse(R"([{"folder":"fit_full","name":"full"},
                                                               {"folder":"fit_single","name":"single"}])"));
  EvalOptions read;
  OptionsFromJson(JsonFields(written, "results.json"), &read);
  EXPECT_EQ(OptionsToJson(read), written);
  EXPECT_EQ(read.results, o.results);
}

TEST(EvalOptionTable, DocsListTheTable) {
  EXPECT_EQ(test::DocSection(SAMP_EVALUATION_DOC, "samp eval --help-options markdown"),
            OptionsMarkdown(EvalOptionTable().Describe()))
      << "docs/evaluation.md's option list differs from the table: regenerate it with "
         "`samp eval --help-options markdown`";
}

}  // namespace
}  // namespace samp
