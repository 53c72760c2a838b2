// synth -> samp fit (library RunFit, joint and single-frame) -> eval on a tiny
// in-memory model of box cars: the whole benchmark chain in seconds.
#include <gtest/gtest.h>

#include <filesystem>
#include <iostream>

#include "libsamp/eval/evaluation.h"
#include "libsamp/synth/synth.h"
#include "libsamp/pipeline/run_fit.h"
#include "tests/synth/test_scene.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

TEST(EndToEnd, SynthFitEval) {
  const std::string root = test::MakeTempFolder("e2e");
  // The clean preset: the chain is tested here, not the realistic scenes.
  SynthOptions synth = test::QuickSynthOptions(root + "/seqs", 21, SynthScene::kClean);
  synth.num_sequences = 1;
  synth.num_frames = 6;
  synth.detector.flip_probability = 0.0;
  const SynthSummary sequences =
      SynthesizeSequences(synth, {{"boxcar", test::MakeBoxCar(4.2)}, {"boxcar_short", test::MakeBoxCar(3.9)}});
  const std::string model_path = root + "/box_model.vdb";
  test::MakeBoxModel().Save(model_path);

  EvalOptions eval;
  eval.sequences = {sequences.sequences[0].folder};
  eval.output_folder = root + "/eval";
  eval.min_segment_pixels = 50;
  for (const bool single_frame : {false, true}) {
    RunFitOptions fit;
    fit.model_path = model_path;
    fit.sequences = eval.sequences;
    fit.output_dir = root + (single_frame ? "/fit_single" : "/fit_full");
    fit.fit.single_frame = single_frame;
    fit.fit.max_iterations = 30;
    const RunFitSummary summary = RunFit(fit);
    ASSERT_EQ(summary.num_sequences_failed, 0);
    ASSERT_GT(summary.num_tracks_fitted, 0);
    eval.results.emplace_back(single_frame ? "single-frame" : "full", fit.output_dir);
  }
  const EvalSummary result = Evaluate(eval);
  std::cout << result.markdown << std::endl;
  ASSERT_GT(result.num_gt_car_frames, 3);
  ASSERT_EQ(result.shape.size(), 3u);  // stereo, full, single-frame
  ASSERT_EQ(result.pose.size(), 3u);   // detections, full, single-frame
  // The chain, not the quality, is tested here (the box model is crude and the
  // true-disparity noise on cars large): fits match most car-frames, their
  // surfaces land on the car at the loosest tau, poses within a metre.
  const size_t tau_05 = 9;
  for (size_t m = 1; m < 3; ++m) {
    EXPECT_GE(result.shape[m].num_matched, result.num_gt_car_frames / 2) << result.shape[m].method;
    EXPECT_GT(result.shape[m].f1[tau_05], 0.4) << result.shape[m].method;
    EXPECT_LT(result.pose[m].all.translation_median, 1.0) << result.pose[m].method;
  }
  EXPECT_TRUE(fs::exists(eval.output_folder + "/results.md"));
  if (!HasFailure()) fs::remove_all(root);
}

}  // namespace
}  // namespace samp
