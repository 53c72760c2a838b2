// synth -> eval: the ground truth of synthetic sequences evaluated as a result
// gives perfect scores and worse baselines; a fragmented result shows the two
// matchings and the tracking figures apart.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "libsamp/data/kitti_io.h"
#include "libsamp/eval/eval_report.h"
#include "libsamp/eval/evaluation.h"
#include "libsamp/synth/synth.h"
#include "tests/synth/test_scene.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

// synth -> eval with the true meshes and poses as the "result": perfect scores;
// the raw stereo and the noisy detections are worse. The labels carry only ry
// (as KITTI's), so the street preset's ego sway (pitch/roll of up to ~1 degree
// between camera and road) is turned off: with it, a car seen at a grazing
// angle from 20 m loses ~12 % of its pixels at 20 cm.
void CheckGroundTruthAsResult(SynthScene scene) {
  const std::string root = test::MakeTempFolder("synth_eval");
  SynthOptions options = test::QuickSynthOptions(root, 5, scene);
  options.ego_pitch_sway_deg = options.ego_roll_sway_deg = options.ego_bounce = 0.0;
  options.ego_max_pitch_offset_deg = 0.0;
  const SynthSummary summary = SynthesizeSequences(options, test::TwoBoxCars());
  EvalOptions eval;
  for (const SynthSequenceInfo& s : summary.sequences) eval.sequences.push_back(s.folder);
  // Each sequence's gt/ holds label_02/<seq>.txt and meshes/track_<id>.ply, as a fit result does;
  // evaluate the first sequence against its own truth.
  eval.sequences.resize(1);
  eval.results.emplace_back("truth", summary.sequences[0].folder + "/gt");
  eval.output_folder = root + "/eval";
  eval.min_segment_pixels = 30;
  const EvalSummary result = Evaluate(eval);
  ASSERT_GT(result.num_gt_car_frames, 3);
  ASSERT_EQ(result.shape.size(), 2u);  // stereo, truth
  const size_t tau_005 = 0;
  EXPECT_EQ(result.shape[1].method, "truth");
  const size_t tau_02 = 3;
  EXPECT_GT(result.shape[1].f1[tau_005], 0.995)
      << "the true mesh at the true pose reproduces the true depth";
  EXPECT_GT(result.shape[1].f1[tau_02], 0.995);
  EXPECT_LT(result.shape[0].f1[tau_005], result.shape[1].f1[tau_005]);
  EXPECT_GT(result.shape[0].f1[9], 0.5) << "noisy true disparity is still close at tau = 0.5";
  ASSERT_EQ(result.pose.size(), 2u);  // detections, truth
  EXPECT_LT(result.pose[1].all.translation_mean, 1e-3);
  EXPECT_LT(result.pose[1].all.yaw_mean_deg, 0.01);
  EXPECT_GT(result.pose[0].all.translation_mean, 0.01);
  for (const char* file : {"results.md", "results.json", "shape.csv", "pose.csv", "per_object.csv",
                           "f1_vs_tau.png", "translation_vs_distance.png"}) {
    EXPECT_TRUE(fs::exists(eval.output_folder + "/" + file)) << file;
  }
  // The aggregation alone writes nothing; the writers give the same tables.
  EvalOptions aggregate_only = eval;
  aggregate_only.output_folder = root + "/not_written";
  const EvalResults results = ComputeEvaluation(aggregate_only);
  EXPECT_FALSE(fs::exists(aggregate_only.output_folder));
  EXPECT_EQ(results.records.size(), size_t(result.num_gt_car_frames));
  EXPECT_EQ(EvalMarkdown(eval, results), result.markdown);
  if (!::testing::Test::HasFailure()) fs::remove_all(root);
}

TEST(SynthEval, GroundTruthAsResultIsPerfectClean) { CheckGroundTruthAsResult(SynthScene::kClean); }
TEST(SynthEval, GroundTruthAsResultIsPerfectStreet) { CheckGroundTruthAsResult(SynthScene::kStreet); }

// The two matchings on a hand-made fragmented output: the ground truth as a
// result, with the last third of one car's frames under a new track id (a
// fragment; its mesh copied). Per frame every car-frame still matches
// perfectly; per track the fragment's car-frames are unmatched; the tracking
// figures see one ID switch and one extra track.
TEST(SynthEval, FragmentedOutputPerFrameVsPerTrack) {
  const std::string root = test::MakeTempFolder("synth_eval_fragment");
  // The clean preset: its true mesh at the true pose is perfect at tau = 0.05
  // (the street labels lack the ego sway's pitch/roll; see above).
  SynthOptions options = test::QuickSynthOptions(root, 5, SynthScene::kClean);
  options.num_sequences = 1;
  const SynthSummary summary = SynthesizeSequences(options, test::TwoBoxCars());
  const std::string seq = summary.sequences[0].name;
  const std::string gt = summary.sequences[0].folder + "/gt";
  const std::string result = root + "/fragmented";
  fs::create_directories(result + "/label_02");
  fs::copy(gt + "/meshes", result + "/meshes", fs::copy_options::recursive);
  std::vector<ObjectLabel> labels = ReadTrackingLabels(gt + "/label_02/" + seq + ".txt");
  std::map<int, std::vector<int>> frames_of_car;
  for (const ObjectLabel& l : labels) frames_of_car[l.track_id].push_back(l.frame);
  int car = -1;
  size_t most = 0;
  for (const auto& [id, frames] : frames_of_car)
    if (frames.size() > most) most = frames.size(), car = id;
  ASSERT_GE(most, 3u);
  std::vector<int> frames = frames_of_car[car];
  std::sort(frames.begin(), frames.end());
  const int split = frames[frames.size() - frames.size() / 3];  // the last third
  const int fragment_id = 100;
  for (ObjectLabel& l : labels)
    if (l.track_id == car && l.frame >= split) l.track_id = fragment_id;
  WriteTrackingLabels(result + "/label_02/" + seq + ".txt", labels);
  fs::copy_file(result + "/meshes/track_" + std::to_string(car) + ".ply",
                result + "/meshes/track_" + std::to_string(fragment_id) + ".ply");

  EvalOptions eval;
  eval.sequences.push_back(summary.sequences[0].folder);
  eval.results.emplace_back("fragmented", result);
  eval.output_folder = root + "/eval";
  eval.min_segment_pixels = 30;
  eval.stereo_baseline = false;
  const EvalSummary r = Evaluate(eval);
  ASSERT_EQ(r.shape.size(), 1u);
  ASSERT_EQ(r.shape_per_frame.size(), 1u);
  const int total = r.num_gt_car_frames;
  ASSERT_GT(total, 3);
  // Per frame: every car-frame matched by the true mesh at the true pose.
  EXPECT_EQ(r.shape_per_frame[0].num_matched, total);
  EXPECT_GT(r.shape_per_frame[0].f1[0], 0.995);
  // Per track: the car's fragment is not its track.
  std::ifstream csv(eval.output_folder + "/per_car.csv");
  std::string line;
  int fragment_frames = 0;
  while (std::getline(csv, line))
    if (line.find(",fragmented,per_frame," + std::to_string(fragment_id) + ",") != std::string::npos)
      ++fragment_frames;
  ASSERT_GT(fragment_frames, 0);
  EXPECT_EQ(r.shape[0].num_matched, total - fragment_frames);
  EXPECT_GT(r.shape[0].f1[0], 0.995) << "the matched car-frames are still perfect";
  ASSERT_EQ(r.pose.size(), 2u);  // detections, fragmented
  EXPECT_EQ(r.pose[1].num_matched, total - fragment_frames);
  EXPECT_EQ(r.pose_per_frame[1].num_matched, total);
  // Tracking: one switch, one more track than cars, nothing missed or false.
  ASSERT_EQ(r.tracking.size(), 1u);
  const TrackingCounts& c = r.tracking[0].counts;
  EXPECT_EQ(c.id_switches, 1);
  EXPECT_EQ(c.fragmentations, 0);
  EXPECT_EQ(c.misses, 0);
  EXPECT_EQ(c.false_positives, 0);
  EXPECT_EQ(c.false_tracks, 0);
  EXPECT_EQ(c.missed_cars, 0);
  EXPECT_EQ(c.tracks_on_cars, c.true_cars + 1);
  EXPECT_NEAR(c.Mota(), 1.0 - 1.0 / c.true_boxes, 1e-12);
  // Diagnostics: the true boxes have no offsets.
  ASSERT_FALSE(r.diagnostics.empty());
  for (const DiagnosticsBand& b : r.diagnostics) {
    if (b.method != "fragmented" || b.count == 0) continue;
    EXPECT_NEAR(b.along_ray_offset, 0.0, 1e-3);
    EXPECT_NEAR(b.abs_lateral_offset, 0.0, 1e-3);
    EXPECT_NEAR(b.size_error.norm(), 0.0, 1e-3);
  }
  for (const char* file : {"per_car.csv", "tracking.csv", "results.md"})
    EXPECT_TRUE(fs::exists(eval.output_folder + "/" + file)) << file;
  fs::remove_all(root);
}

}  // namespace
}  // namespace samp
