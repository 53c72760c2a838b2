// Issue 31's target: one synthetic scene written in samp's layout and in
// KITTI tracking's own layout (`samp synth --layout kitti-tracking`: images,
// calibration with all matrices, oxts, label_02, detections in rectified
// camera 0) and fitted through both readers gives the same labels: ego poses
// within 1 mm and 0.01 deg after the oxts round trip (here within 1e-6 m and
// 1e-6 deg), and labels within 1 mm and 0.2 deg.
//
// Why the labels are not held to 0.01 deg: the oxts round trip leaves ~1e-10 m
// in the ego poses, and the default ray-depth data term has kinks (rays that
// switch between meeting and missing the surface), where the solve stops after
// max_rejected_steps rejected steps. A 1e-10 m difference can move that stop:
// in the clang build one car's yaw ended 2e-4 rad (0.011 deg, two steps of
// the labels' 1e-4 rad) apart, cost 6.4551 against 6.4538; in the g++ build
// the labels were identical. With the fixed detector model used below (see
// there) the g++ build's yaws end 0.086 deg apart, the clang build's 0.006.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>

#include "libsamp/core/pose.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/kitti_tracking.h"
#include "libsamp/eval/evaluation.h"
#include "libsamp/pipeline/run_fit.h"
#include "libsamp/synth/synth.h"
#include "tests/synth/test_scene.h"
#include "tests/testing/expect_error.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

TEST(KittiTrackingLayout, SameLabelsAsSampsLayout) {
  const std::string root = test::MakeTempFolder("kitti_tracking_layout");
  SynthOptions synth = test::QuickSynthOptions(root + "/samp", 31, SynthScene::kClean);
  synth.num_sequences = 1;
  synth.num_frames = 6;
  synth.detector.flip_probability = 0.0;
  const std::vector<SynthCar> cars = {{"boxcar", test::MakeBoxCar(4.2)}, {"boxcar_short", test::MakeBoxCar(3.9)}};
  const SynthSummary samp_scene = SynthesizeSequences(synth, cars);
  synth.output_folder = root + "/kitti";
  synth.layout = SynthLayout::kKittiTracking;
  const SynthSummary kitti_scene = SynthesizeSequences(synth, cars);
  ASSERT_EQ(kitti_scene.sequences.size(), 1u);
  const std::string samp_seq = samp_scene.sequences[0].folder;
  const std::string kitti_seq = kitti_scene.sequences[0].folder;
  EXPECT_EQ(kitti_scene.sequences[0].name, "0000");
  EXPECT_EQ(kitti_seq, root + "/kitti/training/image_02/0000");
  EXPECT_EQ(kitti_scene.sequences[0].num_detections, samp_scene.sequences[0].num_detections);
  EXPECT_EQ(kitti_scene.sequences[0].num_gt_labels, samp_scene.sequences[0].num_gt_labels);
  // The same images, byte for byte.
  for (int t = 0; t < synth.num_frames; ++t) {
    char name[32];
    std::snprintf(name, sizeof(name), "/image_2/000000_%02d.png", t);
    EXPECT_EQ(test::ReadText(samp_seq + name),
              test::ReadText(KittiTrackingLayout(root + "/kitti/training", "0000").LeftImage(t)));
  }
  // KITTI tracking has no disparity or planes: samp's layout without them too
  // (SGBM disparity and RANSAC planes in both).
  fs::remove_all(samp_seq + "/disparity");
  fs::remove_all(samp_seq + "/planes");
  // The ego poses: samp's poses file against the oxts through the calibration.
  const std::vector<Eigen::Isometry3d> samp_poses = ReadPoses(samp_seq + "/poses/000000.txt");
  const std::vector<Eigen::Isometry3d> kitti_poses =
      CameraPosesFromOxts(ReadOxts(root + "/kitti/training/oxts/0000.txt"),
                          ReadKittiTrackingCalibration(root + "/kitti/training/calib/0000.txt"));
  ASSERT_EQ(samp_poses.size(), kitti_poses.size());
  ASSERT_EQ(samp_poses.size(), static_cast<size_t>(synth.num_frames));
  for (size_t k = 0; k < samp_poses.size(); ++k) {
    const Eigen::Isometry3d d = samp_poses[k].inverse() * kitti_poses[k];
    EXPECT_LT(d.translation().norm(), 1e-6) << "frame " << k;
    EXPECT_LT(Eigen::AngleAxisd(d.linear()).angle() * 180.0 / kPi, 1e-6) << "frame " << k;
  }
  const std::string model_path = root + "/box_model.vdb";
  test::MakeBoxModel().Save(model_path);

  RunFitOptions fit;
  fit.model_path = model_path;
  fit.fit.max_iterations = 30;
  // The layouts' inputs differ by rounding (the oxts poses by up to 1e-6 m,
  // the detections by their text). A fit can amplify that: with the detected
  // position's dead zone the stop within the zone moved by 7 mm, and with the
  // self-calibration of these 12 detections (a measured correlation between
  // frames) the clang sanitizer build ended the two fits 6-10 cm apart (other
  // EM associations). The fixed detector model and the plain term keep the
  // two fits within the tolerance below, so the test sees the layouts.
  fit.self_calibrate = false;
  fit.fit.detection_position_dead_zone = 0.0;
  fit.sequences = {samp_seq};
  fit.output_dir = root + "/fit_samp";
  const RunFitSummary samp_fit = RunFit(fit);
  ASSERT_EQ(samp_fit.num_sequences_failed, 0) << samp_fit.BriefReport();
  fit.sequences = {kitti_seq};
  fit.sequence.detections_path = root + "/kitti/detections";
  fit.output_dir = root + "/fit_kitti";
  const RunFitSummary kitti_fit = RunFit(fit);
  ASSERT_EQ(kitti_fit.num_sequences_failed, 0) << kitti_fit.BriefReport();
  ASSERT_GT(kitti_fit.num_tracks_fitted, 0);
  EXPECT_EQ(kitti_fit.num_tracks_fitted, samp_fit.num_tracks_fitted);

  const std::vector<ObjectLabel> a = ReadTrackingLabels(root + "/fit_samp/label_02/000000.txt");
  const std::vector<ObjectLabel> b = ReadTrackingLabels(root + "/fit_kitti/label_02/0000.txt");
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 5u);
  // samp's labels are in camera 2 (the rendering camera), KITTI's in
  // rectified camera 0 = camera 2 - t2.
  const Eigen::Vector3d t2 =
      ReadKittiTrackingCalibration(root + "/kitti/training/calib/0000.txt").Camera2FromRectified0();
  double max_mm = 0, max_deg = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].frame, b[i].frame);
    EXPECT_EQ(a[i].track_id, b[i].track_id);
    max_mm = std::max(max_mm, 1e3 * (a[i].position - t2 - b[i].position).norm());
    max_deg = std::max(max_deg, std::abs(WrapAngle(a[i].rotation_y - b[i].rotation_y)) * 180.0 / kPi);
    max_mm = std::max(max_mm, 1e3 * std::abs(a[i].length - b[i].length));
    EXPECT_LT((a[i].box_2d - b[i].box_2d).cwiseAbs().maxCoeff(), 0.1);
  }
  std::cout << a.size() << " labels: largest position difference " << max_mm << " mm, yaw " << max_deg
            << " deg (labels are written with 0.1 mm and 1e-4 rad)" << std::endl;
  EXPECT_LT(max_mm, 1.0);
  EXPECT_LT(max_deg, 0.2);  // a wrong rotation convention errs by degrees
  // The ground truth in label_02 is the samp layout's, moved to camera 0.
  const std::vector<ObjectLabel> gt_samp = ReadTrackingLabels(samp_seq + "/gt/label_02/000000.txt");
  const std::vector<ObjectLabel> gt_kitti = ReadTrackingLabels(root + "/kitti/training/label_02/0000.txt");
  ASSERT_EQ(gt_samp.size(), gt_kitti.size());
  for (size_t i = 0; i < gt_samp.size(); ++i)
    EXPECT_LT((gt_samp[i].position - t2 - gt_kitti[i].position).norm(), 2e-4);

  // samp eval of the KITTI layout (label_02 as the ground truth, the detections
  // of --detections as the baseline): pose and tracking only, and per car-frame
  // the same pose errors as the evaluation of the same fit in samp's layout.
  EvalOptions eval;
  eval.sequences = {kitti_seq};
  eval.results = {{"fit", root + "/fit_kitti"}};
  eval.detections_path = root + "/kitti/detections";
  eval.output_folder = root + "/eval_kitti";
  eval.min_box_height_px = 0;
  const EvalResults kitti_eval = ComputeEvaluation(eval);
  EXPECT_TRUE(kitti_eval.without_maps);
  EXPECT_TRUE(kitti_eval.summary.shape.empty());
  ASSERT_EQ(kitti_eval.summary.pose.size(), 2u);
  EXPECT_EQ(kitti_eval.summary.pose[0].method, "detections");
  ASSERT_EQ(kitti_eval.summary.tracking.size(), 1u);
  EXPECT_EQ(kitti_eval.summary.tracking[0].counts.id_switches, 0);
  eval.sequences = {samp_seq};
  eval.results = {{"fit", root + "/fit_samp"}};
  eval.stereo_baseline = false;  // its disparity was removed above
  eval.output_folder = root + "/eval_samp";
  const EvalResults samp_eval = ComputeEvaluation(eval);
  EXPECT_FALSE(samp_eval.without_maps);
  std::map<std::pair<int, int>, const CarFrameRecord*> samp_records;
  for (const CarFrameRecord& r : samp_eval.records) samp_records[{r.track_id, r.frame}] = &r;
  int compared = 0;
  for (const CarFrameRecord& r : kitti_eval.records) {
    const auto found = samp_records.find({r.track_id, r.frame});
    if (found == samp_records.end()) continue;
    for (size_t m = 0; m < 2; ++m) {  // detections, fit
      const MethodCarFrame& a = r.methods[kPerFrame][m];
      const MethodCarFrame& b = found->second->methods[kPerFrame][m];
      ASSERT_EQ(a.matched, b.matched) << "track " << r.track_id << " frame " << r.frame;
      if (!a.matched) continue;
      EXPECT_NEAR(a.translation_error, b.translation_error, 1e-3) << "track " << r.track_id << " frame " << r.frame;
      EXPECT_NEAR(a.yaw_error_deg, b.yaw_error_deg, 0.2);
      ++compared;
    }
  }
  EXPECT_GT(compared, 10);
  // Mixed layouts are refused.
  eval.sequences = {samp_seq, kitti_seq};
  test::ExpectError([&] { ComputeEvaluation(eval); }, {"1 of the 2 sequences are of KITTI tracking's layout"});
  if (!HasFailure()) fs::remove_all(root);
}

}  // namespace
}  // namespace samp
