// Outputs of a fit: KITTI result lines in each frame's camera, aligned
// observations, the fitted surface and the JSON record.
#include "libsamp/pipeline/fit_output.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/fit/fit_test_util.h"

namespace samp {
namespace {

const ShapeLookup& Lookup() {
  static const ShapeModel model = testing::MakeSyntheticModel(5, 0.1);
  static const ShapeLookup lookup(model);
  return lookup;
}

// A two-frame fit seen from a moving, yawed ego camera.
void MakeFit(Track* track, TrackFit* fit) {
  track->id = 7;
  track->sequence = "000001";
  fit->track_id = 7;
  fit->shape_code = 0.5 * Lookup().sigmas();
  for (int k = 0; k < 2; ++k) {
    TrackFrame tf;
    tf.frame = 4 + k;
    tf.time = 0.1 * tf.frame;
    tf.world_from_camera = WorldFromObject(Eigen::Vector3d(0.3 * k, 0.0, 1.0 * k), 0.1 * k);
    tf.detection.score = 0.8;
    track->frames.push_back(tf);
    FrameFit ff;
    ff.frame = tf.frame;
    ff.time = tf.time;
    ff.position = Eigen::Vector3d(2.0 + k, 1.65, 12.0);
    ff.yaw = M_PI - 0.05 + 0.1 * k;  // crosses +-pi
    ff.points_in_world = {ff.WorldFromObject() * Eigen::Vector3d(1.0, -0.5, 0.8),
                          ff.WorldFromObject() * Eigen::Vector3d(-2.0, -1.0, -0.7)};
    ff.num_points = 2;
    fit->frames.push_back(ff);
  }
}

TEST(FitOutput, LabelsInEachFramesCamera) {
  Track track;
  TrackFit fit;
  MakeFit(&track, &fit);
  const std::vector<ObjectLabel> labels = FitToLabels(fit, track, Lookup());
  ASSERT_EQ(labels.size(), 2u);
  const AlignedBox box = FittedBox(Lookup(), fit.shape_code);
  ASSERT_FALSE(box.IsEmpty());
  for (int k = 0; k < 2; ++k) {
    const ObjectLabel& l = labels[k];
    const Eigen::Isometry3d camera_from_world = track.frames[k].world_from_camera.inverse();
    EXPECT_EQ(l.frame, 4 + k);
    EXPECT_EQ(l.track_id, 7);
    EXPECT_LT((l.position - camera_from_world * fit.frames[k].position).norm(), 1e-9);
    // The label pose (KITTI convention) places the object frame like the fit.
    const Eigen::Isometry3d from_label = WorldFromObject(l.position, l.rotation_y);
    const Eigen::Isometry3d expected = camera_from_world * fit.frames[k].WorldFromObject();
    EXPECT_LT((from_label.matrix() - expected.matrix()).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_GT(l.rotation_y, -M_PI);
    EXPECT_LE(l.rotation_y, M_PI);
    EXPECT_NEAR(WrapAngle(l.alpha - (l.rotation_y - std::atan2(l.position.x(), l.position.z()))), 0, 1e-12);
    EXPECT_NEAR(l.length, box.Size().x(), 1e-12);
    EXPECT_NEAR(l.height, box.Size().y(), 1e-12);
    EXPECT_NEAR(l.width, box.Size().z(), 1e-12);
    EXPECT_GT(l.length, 3.0);
    EXPECT_NEAR(l.score, 0.8, 1e-12);
    // The projected object centre lies inside the 2D box.
    const Eigen::Vector2d uv = track.calibration.camera.Project(expected * box.Center());
    EXPECT_GE(uv.x(), l.box_2d[0]);
    EXPECT_LE(uv.x(), l.box_2d[2]);
    EXPECT_GE(uv.y(), l.box_2d[1]);
    EXPECT_LE(uv.y(), l.box_2d[3]);
  }
}

TEST(FitOutput, AlignedObservationsAndSurface) {
  Track track;
  TrackFit fit;
  MakeFit(&track, &fit);
  const PointCloud cloud = AlignedObservations(fit);
  ASSERT_EQ(cloud.points.size(), 4u);
  ASSERT_EQ(cloud.colors.size(), 4u);
  EXPECT_LT((cloud.points[0].cast<double>() - Eigen::Vector3d(1.0, -0.5, 0.8)).norm(), 1e-5);
  EXPECT_LT((cloud.points[3].cast<double>() - Eigen::Vector3d(-2.0, -1.0, -0.7)).norm(), 1e-5);
  const Mesh mesh = FittedSurface(Lookup(), fit.shape_code);
  ASSERT_FALSE(mesh.Empty());
  double worst = 0;
  for (const auto& v : mesh.vertices) {
    worst = std::max(worst, std::abs(Lookup().Evaluate(fit.shape_code, v.cast<double>())));
  }
  EXPECT_LT(worst, 0.1);  // on the zero level set within a voxel
}

TEST(FitOutput, JsonRecord) {
  Track track;
  TrackFit fit;
  MakeFit(&track, &fit);
  fit.summary.solves.resize(2);
  fit.summary.initial_cost = 3.0;
  fit.summary.final_cost = 1.0;
  const nlohmann::json j = TrackFitToJson(fit, FittedBox(Lookup(), fit.shape_code));
  EXPECT_EQ(j["track_id"], 7);
  EXPECT_EQ(j["mode"], "joint");
  EXPECT_EQ(j["shape_code"].size(), 5u);
  EXPECT_EQ(j["frames"].size(), 2u);
  EXPECT_EQ(j["frames"][1]["frame"], 5);
  EXPECT_EQ(j["frames"][0]["position_world"].size(), 3u);
  EXPECT_EQ(j["summary"]["solves"].size(), 2u);
  EXPECT_DOUBLE_EQ(j["summary"]["final_cost"].get<double>(), 1.0);
  const nlohmann::json o = FitOptionsToJson(FitOptions());
  EXPECT_EQ(o["em_iterations"], 1);
  EXPECT_EQ(o["linear_solver"], "sparse_normal_cholesky");
}

}  // namespace
}  // namespace samp
