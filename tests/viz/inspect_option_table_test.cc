// The option tables of inspecting a model file (viz/inspect_option_table.h):
// Check() names the field, its rule and the value, each command-line option
// sets its own member, and docs/inspect.md's lists are the tables'
// (regenerate: `samp inspect --help-options markdown`, `meshes-markdown`,
// `encode-markdown`, `pictures-markdown`).
#include <gtest/gtest.h>

#include "libsamp/viz/inspect_option_table.h"
#include "tests/testing/expect_error.h"
#include "tests/testing/option_table_checks.h"

namespace samp {
namespace {

TEST(InspectOptionTables, CheckNamesTheFieldTheRuleAndTheValue) {
  InspectOptions o;
  test::ExpectError([&] { o.Check(); }, {"InspectOptions.model_path must be given, got "});
  o.model_path = "m.vdb";
  o.encode_folder = "enc";
  test::ExpectError([&] { o.Check(); }, {"InspectOptions.encode_folder must be empty without --encode, got enc"});
  o.encode_input = "car.obj";
  EXPECT_NO_THROW(o.Check());
  EigenShapeMeshOptions meshes;
  meshes.output_folder = "out";
  EXPECT_NO_THROW(meshes.Check());
  meshes.format = "stl";
  test::ExpectError([&] { meshes.Check(); }, {"EigenShapeMeshOptions.format must be one of ply, obj, glb, got stl"});
  meshes.format = "ply";
  meshes.ks.clear();
  test::ExpectError([&] { meshes.Check(); }, {"EigenShapeMeshOptions.ks must be a non-empty list, got "});
  EncodeOptions encode;
  test::ExpectError([&] { encode.Check(); }, {"EncodeOptions.input must be given, got "});
  encode.input = "car.obj";
  encode.prior_weight = -1;
  test::ExpectError([&] { encode.Check(); }, {"EncodeOptions.prior_weight must be >= 0, got -1"});
  PictureOptions pictures;
  pictures.output_folder = "png";
  pictures.num_sheet_shapes = 51;
  test::ExpectError([&] { pictures.Check(); }, {"PictureOptions.num_sheet_shapes must be in [1, 50], got 51"});
}

// Each field's binding sets its own member (and no other field's text).
template <typename S>
void ExpectEachBindingSetsItsMember(const OptionTable<S>& table) {
  for (const OptionInfo& info : table.Describe()) {
    S o;
    std::map<std::string, std::string> before, after;
    for (const OptionBinding& b : table.Bind(&o)) before[b.info.name] = b.info.default_text;
    for (const OptionBinding& b : table.Bind(&o)) {
      if (b.info.name == info.name) b.set(test::OtherValue(info));
    }
    for (const OptionBinding& b : table.Bind(&o)) after[b.info.name] = b.info.default_text;
    for (const auto& [name, text] : before) {
      EXPECT_EQ(after[name] != text, name == info.name) << info.name << ": " << name;
    }
  }
}

TEST(InspectOptionTables, EveryOptionSetsItsOwnMember) {
  ExpectEachBindingSetsItsMember(InspectOptionTable());
  ExpectEachBindingSetsItsMember(EigenShapeMeshOptionTable());
  ExpectEachBindingSetsItsMember(EncodeOptionTable());
  ExpectEachBindingSetsItsMember(PictureOptionTable());
}

TEST(InspectOptionTables, DocsListTheTables) {
  EXPECT_EQ(test::DocSection(SAMP_INSPECT_DOC, "samp inspect --help-options markdown"),
            OptionsMarkdown(InspectOptionTable().Describe()));
  EXPECT_EQ(test::DocSection(SAMP_INSPECT_DOC, "samp inspect --help-options meshes-markdown"),
            OptionsMarkdown(EigenShapeMeshOptionTable().Describe()));
  EXPECT_EQ(test::DocSection(SAMP_INSPECT_DOC, "samp inspect --help-options encode-markdown"),
            OptionsMarkdown(EncodeOptionTable().Describe()));
  EXPECT_EQ(test::DocSection(SAMP_INSPECT_DOC, "samp inspect --help-options pictures-markdown"),
            OptionsMarkdown(PictureOptionTable().Describe()))
      << "docs/inspect.md's option lists differ from the tables: regenerate them with "
         "`samp inspect --help-options markdown` (and meshes-, encode-, pictures-markdown)";
}

}  // namespace
}  // namespace samp
