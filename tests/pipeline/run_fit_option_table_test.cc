// The option table of a `samp fit` run (pipeline/run_fit_option_table.h):
// Check() names the field, its rule and the value, every field is wired to its
// own member, config.json keeps its keys (self_calibrate and detector_model
// only when used), and docs/fitting.md's list is the table's (regenerate:
// `samp fit --help-options run-markdown`).
#include <gtest/gtest.h>

#include "libsamp/pipeline/fit_config.h"
#include "libsamp/pipeline/run_fit_option_table.h"
#include "tests/testing/expect_error.h"
#include "tests/testing/option_table_checks.h"

namespace samp {
namespace {

std::vector<std::string> JsonKeys(const nlohmann::json& j) {
  std::vector<std::string> keys;
  for (auto it = j.begin(); it != j.end(); ++it) keys.push_back(it.key());
  return keys;
}

RunFitOptions ValidOptions() {
  RunFitOptions o;
  o.model_path = "model.vdb";
  o.sequences = {"seq"};
  o.output_dir = "out";
  return o;
}

TEST(RunFitOptionTable, CheckNamesTheFieldTheRuleAndTheValue) {
  EXPECT_NO_THROW(ValidOptions().Check());
  RunFitOptions o = ValidOptions();
  o.model_path.clear();
  test::ExpectError([&] { o.Check(); }, {"RunFitOptions.model must be given unless link_only, got "});
  o.link_only = true;
  EXPECT_NO_THROW(o.Check());
  o = ValidOptions();
  o.sequences.clear();
  test::ExpectError([&] { o.Check(); }, {"RunFitOptions.sequences must be given (at least one --seq), got "});
  o = ValidOptions();
  o.tracking_labels = {"a.txt", "b.txt"};
  test::ExpectError([&] { o.Check(); },
                    {"RunFitOptions.tracking_labels must be empty or one per sequence, got a.txt,b.txt"});
  o = ValidOptions();
  o.output_dir.clear();
  test::ExpectError([&] { o.Check(); }, {"RunFitOptions.output_dir must be given, got "});
  o = ValidOptions();
  o.num_threads = -1;
  test::ExpectError([&] { o.Check(); }, {"RunFitOptions.num_threads must be >= 0, got -1"});
  // The nested structs after the run's own fields.
  o = ValidOptions();
  o.sequence.object_types = {"Car", ""};
  test::ExpectError([&] { o.Check(); }, {"SequenceOptions.object_types must be a non-empty list of names, got Car,"});
}

TEST(RunFitOptionTable, EveryFieldIsWiredToItsOwnMember) {
  test::ExpectEveryFieldWired(RunFitOptionTable(), "", {"fit.", "sequence.", "calibration."});
  test::ExpectJsonRoundTrip(RunFitOptionTable());
}

// The keys of config.json written before the table; self_calibrate (off) and
// the detector model only when used.
TEST(RunFitOptionTable, JsonKeepsConfigJsonsKeys) {
  RunFitOptions o;
  o.self_calibrate = false;
  EXPECT_EQ(JsonKeys(OptionsToJson(o)),
            (std::vector<std::string>{"fit", "link_only", "model", "num_threads", "output_dir", "sequence",
                                      "sequences", "tracking_labels", "write_meshes"}));
  o.self_calibrate = true;
  o.detector_model_path = "detector.json";
  o.sequences = {"a", "b"};
  const nlohmann::json j = OptionsToJson(o);
  EXPECT_EQ(j.at("self_calibrate"), true);
  EXPECT_EQ(j.at("detector_model"), "detector.json");
  EXPECT_EQ(j.at("sequences"), nlohmann::json::array({"a", "b"}));
  RunFitOptions read;
  OptionsFromJson(JsonFields(j, "config.json"), &read);
  EXPECT_EQ(OptionsToJson(read), j);
}

// JsonDefaults::kWrite (the Python options objects) also writes the optional
// fields at their default, nested ones included; reading it back gives the same
// struct, and the file form (kOmit) is unchanged.
TEST(RunFitOptionTable, JsonCanListEveryField) {
  RunFitOptions o;
  o.self_calibrate = false;  // the value that config.json omits
  const nlohmann::json omitted = OptionsToJson(o);
  const nlohmann::json every = OptionsToJson(o, JsonDefaults::kWrite);
  for (const char* key : {"self_calibrate", "detector_model", "detector_plot", "calibration"}) {
    EXPECT_FALSE(omitted.contains(key)) << key;
    EXPECT_TRUE(every.contains(key)) << key;
  }
  EXPECT_EQ(every.at("detector_plot"), true);
  EXPECT_TRUE(every.at("sequence").contains("detections"));
  EXPECT_FALSE(omitted.at("sequence").contains("detections"));
  for (auto it = omitted.begin(); it != omitted.end(); ++it) {
    if (!it.value().is_object()) EXPECT_EQ(every.at(it.key()), it.value()) << it.key();
  }
  RunFitOptions read;
  read.detector_plot = false;
  read.self_calibrate = true;
  OptionsFromJson(JsonFields(every, "options"), &read);
  EXPECT_EQ(OptionsToJson(read), omitted);
  EXPECT_EQ(OptionsToJson(read, JsonDefaults::kWrite), every);
}

// A list set from a command line: each value as given (a comma in a path stays).
TEST(RunFitOptionTable, ListsTakeEachValueAsGiven) {
  RunFitOptions o;
  for (const OptionBinding& b : RunFitOptionTable().Bind(&o)) {
    if (b.info.name == "sequences") b.set_list({"a,b", "c"});
  }
  EXPECT_EQ(o.sequences, (std::vector<std::string>{"a,b", "c"}));
}

TEST(RunFitOptionTable, DocsListTheTable) {
  EXPECT_EQ(test::DocSection(SAMP_FITTING_DOC, "samp fit --help-options run-markdown"),
            OptionsMarkdown(RunFitOptionTable().Describe()))
      << "docs/fitting.md's run option list differs from the table: regenerate it with "
         "`samp fit --help-options run-markdown`";
}

}  // namespace
}  // namespace samp
