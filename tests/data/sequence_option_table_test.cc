// The option tables of reading a sequence (data/sequence_option_table.h):
// Check() names the field, its rule and the value, every field is wired to its
// own member, the JSON keeps config.json's keys, and docs/sequence_format.md's
// lists are the tables' (regenerate: `samp fit --help-options stereo-markdown`,
// `road-markdown`).
#include <gtest/gtest.h>

#include "libsamp/data/sequence_option_table.h"
#include "tests/testing/expect_error.h"
#include "tests/testing/option_table_checks.h"

namespace samp {
namespace {

std::vector<std::string> JsonKeys(const nlohmann::json& j) {
  std::vector<std::string> keys;
  for (auto it = j.begin(); it != j.end(); ++it) keys.push_back(it.key());
  return keys;
}

TEST(SequenceOptionTables, CheckNamesTheFieldTheRuleAndTheValue) {
  EXPECT_NO_THROW(StereoOptions().Check());
  EXPECT_NO_THROW(RoadPlaneOptions().Check());
  StereoOptions s;
  s.num_disparities = 100;
  test::ExpectError([&] { s.Check(); }, {"StereoOptions.num_disparities must be a multiple of 16, got 100"});
  s = StereoOptions();
  s.block_size = 4;
  test::ExpectError([&] { s.Check(); }, {"StereoOptions.block_size must be odd, got 4"});
  s = StereoOptions();
  s.p1 = 10;
  s.p2 = 5;
  test::ExpectError([&] { s.Check(); }, {"StereoOptions.p2 must be > p1 when both are set, got 5"});
  s = StereoOptions();
  s.mode = "fast";
  test::ExpectError([&] { s.Check(); }, {"StereoOptions.mode must be one of sgbm, hh, 3way, hh4, got fast"});
  RoadPlaneOptions r;
  r.min_camera_height = 3.5;
  test::ExpectError([&] { r.Check(); }, {"RoadPlaneOptions.min_camera_height must be < max_camera_height, got 3.5"});
  r = RoadPlaneOptions();
  r.max_tilt_deg = 90;
  test::ExpectError([&] { r.Check(); }, {"RoadPlaneOptions.max_tilt_deg must be in (0, 90), got 90"});
}

// SequenceOptions' own fields: the rules, and config.json's "sequence" with the
// nested structs, the object types and the detections only when given.
TEST(SequenceOptionTables, SequenceOptionsJsonAndRules) {
  SequenceOptions o;
  o.first_frame = 9;
  o.last_frame = 3;
  test::ExpectError([&] { o.Check(); }, {"SequenceOptions.last_frame must be >= first_frame, got 3"});
  o = SequenceOptions();
  o.detection_format = "csv";
  test::ExpectError([&] { o.Check(); },
                    {"SequenceOptions.detection_format must be one of auto, kitti-object, kitti-tracking, ab3dmot, "
                     "got csv"});
  EXPECT_EQ(JsonKeys(OptionsToJson(SequenceOptions())),
            (std::vector<std::string>{"first_frame", "last_frame", "min_detection_score", "object_types",
                                      "observations", "road_plane", "stereo", "tracker", "tracking_labels_path"}));
  o = SequenceOptions();
  o.detections_path = "dets";
  o.detection_format = "ab3dmot";
  o.object_types = {"Car", "Van"};
  o.min_detection_score = 0.5;
  const nlohmann::json j = OptionsToJson(o);
  EXPECT_EQ(j.at("detections"), "dets");
  EXPECT_EQ(j.at("detection_format"), "ab3dmot");
  SequenceOptions read;
  OptionsFromJson(JsonFields(j, "config.json"), &read);
  EXPECT_EQ(OptionsToJson(read), j);
  EXPECT_EQ(read.object_types, o.object_types);
}

TEST(SequenceOptionTables, EveryFieldIsWiredToItsOwnMember) {
  test::ExpectEveryFieldWired(StereoOptionTable(), "stereo-");
  test::ExpectJsonRoundTrip(StereoOptionTable());
  test::ExpectEveryFieldWired(RoadPlaneOptionTable(), "road-");
  test::ExpectJsonRoundTrip(RoadPlaneOptionTable());
}

TEST(SequenceOptionTables, JsonKeepsConfigJsonsKeys) {
  EXPECT_EQ(JsonKeys(OptionsToJson(StereoOptions())),
            (std::vector<std::string>{"block_size", "disp12_max_diff", "min_disparity", "mode", "num_disparities", "p1",
                                      "p2", "pre_filter_cap", "speckle_range", "speckle_window_size",
                                      "uniqueness_ratio"}));
  EXPECT_EQ(JsonKeys(OptionsToJson(RoadPlaneOptions())),
            (std::vector<std::string>{"inlier_threshold", "iterations", "max_camera_height", "max_depth",
                                      "max_points", "max_tilt_deg", "min_camera_height", "min_inliers",
                                      "min_point_height_below_camera", "seed"}));
}

TEST(SequenceOptionTables, DocsListTheTables) {
  EXPECT_EQ(test::DocSection(SAMP_SEQUENCE_FORMAT_DOC, "samp fit --help-options stereo-markdown"),
            OptionsMarkdown(StereoOptionTable().Describe(), "stereo-"))
      << "docs/sequence_format.md's stereo option list differs from the table: regenerate it with "
         "`samp fit --help-options stereo-markdown`";
  EXPECT_EQ(test::DocSection(SAMP_SEQUENCE_FORMAT_DOC, "samp fit --help-options input-markdown"),
            OptionsMarkdown(SequenceOptionTable().Describe()))
      << "docs/sequence_format.md's input option list differs from the table: regenerate it with "
         "`samp fit --help-options input-markdown`";
  EXPECT_EQ(test::DocSection(SAMP_SEQUENCE_FORMAT_DOC, "samp fit --help-options road-markdown"),
            OptionsMarkdown(RoadPlaneOptionTable().Describe(), "road-"))
      << "docs/sequence_format.md's road-plane option list differs from the table: regenerate it with "
         "`samp fit --help-options road-markdown`";
}

}  // namespace
}  // namespace samp
