// Synthesis: determinism by seed, the sequence layout `samp fit` reads, the
// motion model of the ground truth, the street's sway, parked cars and stereo
// quality, the near share and the option checks (the ground truth evaluated
// against itself: tests/eval/synth_eval_test.cc).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "libsamp/core/error.h"
#include "libsamp/core/wheels.h"
#include "libsamp/scan/mesh_io.h"
#include "libsamp/synth/synth.h"
#include "libsamp/data/detector_noise.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/sequence.h"
#include "libsamp/fit/fitter.h"
#include "libsamp/fit/motion_model.h"
#include "tests/synth/test_scene.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

// The ground truth is generated with the model the fitter predicts with: for
// each motion of the synthetic cars, the fitter's model (selected with the
// fitter's default thresholds) predicts every next ground-truth pose from the
// previous one, across the yaw wrap at +-pi and backwards from the middle frame.
TEST(SynthTest, GroundTruthFollowsTheFittersMotionModel) {
  const FitOptions fit;
  struct Case {
    double speed, yaw_rate;
    MotionModel model;
  };
  for (const Case& c : {Case{0.0, 0.0, MotionModel::kStanding}, Case{9.0, 0.0, MotionModel::kStraight},
                        Case{5.0, 0.4, MotionModel::kArc}, Case{3.0, -0.25, MotionModel::kArc}}) {
    EXPECT_EQ(SelectMotionModel(c.speed, c.yaw_rate, fit.standing_speed, fit.straight_yaw_rate), c.model);
    const Eigen::Vector4d origin(2.0, 1.65, 15.0, 3.1);
    const std::vector<Eigen::Vector4d> poses = SynthTrajectory(origin, c.speed, c.yaw_rate, 21, 10, 10.0);
    ASSERT_EQ(poses.size(), 21u);
    EXPECT_EQ(poses[10], origin);
    const double velocity[2] = {c.speed, c.yaw_rate};
    for (int t = 0; t + 1 < 21; ++t) {
      double predicted[6];
      PredictMotion(c.model, poses[t].data(), velocity, 0.1, predicted, nullptr, nullptr);
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(predicted[k], poses[t + 1][k], 1e-9) << "frame " << t;
      EXPECT_NEAR(WrapAngle(predicted[3] - poses[t + 1][3]), 0.0, 1e-12) << "frame " << t;
      EXPECT_EQ(predicted[4], c.model == MotionModel::kStanding ? 0.0 : c.speed);
      EXPECT_EQ(predicted[5], c.model == MotionModel::kArc ? c.yaw_rate : 0.0);
      EXPECT_GT(poses[t][3], -M_PI);
      EXPECT_LE(poses[t][3], M_PI);
    }
  }
}

std::map<std::string, std::string> ReadTree(const std::string& root) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (!entry.is_regular_file()) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    files[fs::relative(entry.path(), root).generic_string()] =
        std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  return files;
}

TEST(Synth, DeterministicBySeed) {
  const std::string a = test::MakeTempFolder("synth_a"), b = test::MakeTempFolder("synth_b"),
                    c = test::MakeTempFolder("synth_c");
  SynthesizeSequences(test::QuickSynthOptions(a, 11), test::TwoBoxCars());
  SynthesizeSequences(test::QuickSynthOptions(b, 11), test::TwoBoxCars());
  SynthesizeSequences(test::QuickSynthOptions(c, 12), test::TwoBoxCars());
  const auto files_a = ReadTree(a), files_b = ReadTree(b), files_c = ReadTree(c);
  ASSERT_GT(files_a.size(), 50u);
  EXPECT_EQ(files_a.size(), files_b.size());
  for (const auto& [name, content] : files_a) {
    ASSERT_TRUE(files_b.count(name)) << name;
    EXPECT_TRUE(files_b.at(name) == content) << name << " differs between two runs with the same seed";
  }
  int differing = 0;
  for (const auto& [name, content] : files_a) {
    if (!files_c.count(name) || files_c.at(name) != content) ++differing;
  }
  EXPECT_GT(differing, 20) << "another seed must give other scenes";
  for (const auto& folder : {a, b, c}) fs::remove_all(folder);
}

void CheckLayout(SynthScene scene) {
  const std::string root = test::MakeTempFolder("synth_layout");
  SynthOptions options = test::QuickSynthOptions(root, 3, scene);
  options.num_sequences = 1;
  const SynthSummary summary = SynthesizeSequences(options, test::TwoBoxCars());
  ASSERT_EQ(summary.sequences.size(), 1u);
  if (scene == SynthScene::kClean) {
    EXPECT_EQ(summary.num_tracks, 2);
  } else {
    EXPECT_GE(summary.num_tracks, 2);
    EXPECT_LE(summary.num_tracks, 3);
  }
  const std::string seq_dir = summary.sequences[0].folder;
  EXPECT_EQ(fs::path(seq_dir).filename().string(), "000000");

  const SequenceFiles files = ListSequence(seq_dir);
  EXPECT_EQ(files.name, "000000");
  ASSERT_EQ(files.frames.size(), 5u);
  const StereoCalibration calibration = ReadCalibration(files.calibration, options.width, options.height);
  EXPECT_NEAR(calibration.baseline, options.baseline, 1e-6);
  EXPECT_NEAR(calibration.camera.fx, options.focal_px, 1e-4);
  const auto poses = ReadPoses(files.poses);
  ASSERT_EQ(poses.size(), 5u);
  EXPECT_TRUE(poses[0].isApprox(Eigen::Isometry3d::Identity()));
  std::vector<Eigen::Vector4d> planes;
  for (const FrameFiles& frame : files.frames) {
    EXPECT_FALSE(frame.image_left.empty());
    EXPECT_FALSE(frame.image_right.empty());
    const cv::Mat disparity = ReadDisparity(frame.disparity, cv::Size(options.width, options.height));
    EXPECT_GT(cv::countNonZero(disparity), options.width * options.height / 2);
    planes.push_back(ReadPlane(frame.plane));
    EXPECT_NEAR(planes.back().head<3>().norm(), 1.0, 1e-6);
    EXPECT_NEAR(planes.back()[3], options.camera_height, 0.05);
    ReadLabels(frame.detections);  // parses
  }
  // The road plane is one plane in the world: every frame's plane, moved to
  // frame 0 by the poses, is frame 0's plane.
  for (size_t t = 0; t < planes.size(); ++t) {
    const Eigen::Vector3d n_world = poses[t].linear() * planes[t].head<3>();
    const double d_world = planes[t][3] - n_world.dot(poses[t].translation());
    EXPECT_NEAR((n_world - planes[0].head<3>()).norm(), 0.0, 1e-4) << "frame " << t;
    EXPECT_NEAR(d_world, planes[0][3], 1e-3) << "frame " << t;
  }
  // Ground truth: labels, object maps consistent with the labels, meshes.
  const auto gt = ReadTrackingLabels(seq_dir + "/gt/label_02/000000.txt");
  ASSERT_FALSE(gt.empty());
  for (const ObjectLabel& label : gt) {
    EXPECT_GE(label.track_id, 0);
    EXPECT_LT(label.track_id, summary.num_tracks);
    const Eigen::Vector4d& plane = planes.at(label.frame);
    EXPECT_NEAR(plane.head<3>().dot(label.position) + plane[3], 0.0, 1e-3) << "cars stand on the road";
    EXPECT_GE(label.position.norm(), 3.0);
    const cv::Mat object_map =
        cv::imread(seq_dir + "/gt/obj_map/000000_0" + std::to_string(label.frame) + ".png",
                   cv::IMREAD_UNCHANGED);
    ASSERT_EQ(object_map.type(), CV_8UC1);
    EXPECT_GT(cv::countNonZero(object_map == label.track_id + 1), 0)
        << "a labelled car is visible in its frame";
  }
  EXPECT_TRUE(fs::exists(seq_dir + "/gt/meshes/track_0.ply"));
  EXPECT_TRUE(fs::exists(seq_dir + "/gt/cars.json"));
  EXPECT_TRUE(fs::exists(root + "/config.json"));
  // The detector's true noise model beside the ground truth, for `samp fit --detector-model`.
  const DetectorNoiseModel true_model = ReadDetectorNoiseModel(seq_dir + "/gt/detector_model.json");
  EXPECT_EQ(true_model.ToJson(),
            TrueDetectorNoiseModel(options.detector, options.min_distance, options.max_distance).ToJson());
  fs::remove_all(root);
}

TEST(Synth, WritesTheLayoutFitReadsStreet) { CheckLayout(SynthScene::kStreet); }
TEST(Synth, WritesTheLayoutFitReadsClean) { CheckLayout(SynthScene::kClean); }

// The street preset's ego camera sways (pitch/roll written to poses/), its
// disparity statistics are reported, its parked cars are written as such.
TEST(Synth, StreetSwayParkedCarsAndStereoQuality) {
  const std::string root = test::MakeTempFolder("synth_street");
  SynthOptions options = test::QuickSynthOptions(root, 5);
  options.num_sequences = 3;
  options.min_ego_speed = 8.0;
  options.parked_cars_per_sequence = 2;
  const SynthSummary summary = SynthesizeSequences(options, test::TwoBoxCars());
  double max_tilt_deg = 0.0;
  for (const SynthSequenceInfo& s : summary.sequences) {
    for (const Eigen::Isometry3d& pose : ReadPoses(s.folder + "/poses/" + s.name + ".txt")) {
      const Eigen::Vector3d up = pose.linear() * Eigen::Vector3d::UnitY();
      max_tilt_deg = std::max(max_tilt_deg, std::acos(std::clamp(up.y(), -1.0, 1.0)) * 180.0 / 3.14159265358979);
    }
  }
  EXPECT_GT(max_tilt_deg, 0.05) << "the camera pitches/rolls relative to frame 0";
  EXPECT_LT(max_tilt_deg, 3.0);
  EXPECT_GT(summary.num_parked, 0);
  EXPECT_GT(summary.car_disparity_valid_fraction, 0.5);
  EXPECT_GT(summary.car_disparity_mae_px, 0.1);
  EXPECT_LT(summary.car_disparity_mae_px, 5.0);
  fs::remove_all(root);
}

// A wheel-less body gets AddWheels' tyres (as Canonicalize does for the Debian
// bodies): rendered in the street preset, the car's lowest visible points lie
// on the road and the pixels below the body's ground clearance exist (tyres).
TEST(Synth, RenderedCarHasWheelsOnTheRoad) {
  Mesh body = MakeBoxMesh(Eigen::Vector3d(-2.1, -0.75, -0.85), Eigen::Vector3d(2.1, 0.0, 0.85));
  body.Append(MakeBoxMesh(Eigen::Vector3d(-1.2, -1.35, -0.75), Eigen::Vector3d(0.9, -0.75, 0.75)));
  const WheelOptions wheel_options;
  const WheeledCar wheeled = AddWheels(body, wheel_options);
  const SynthCar car{"wheeled_box", wheeled.Combined(), int(body.triangles.size())};
  const std::string root = test::MakeTempFolder("synth_wheels");
  SynthOptions options = test::QuickSynthOptions(root, 8);
  options.width = 1242;  // full resolution: the tyres must cover pixels
  options.height = 375;
  options.focal_px = 721.5377;
  options.cx_px = 609.5593;
  options.cy_px = 172.854;
  options.num_sequences = 1;
  options.num_frames = 3;
  options.max_distance = 15.0;
  options.cars_per_sequence = 2;
  options.parked_cars_per_sequence = 2;
  const SynthSummary summary = SynthesizeSequences(options, {car});
  ASSERT_EQ(summary.sequences.size(), 1u);
  ASSERT_GE(summary.num_tracks, 1);
  const std::string seq = summary.sequences[0].folder;
  const Mesh written = LoadMesh(seq + "/gt/meshes/track_0.ply");
  EXPECT_NEAR(written.Bounds().max.y(), 0.0, 1e-4) << "the ground-truth mesh includes the tyres, touching y = 0";
  EXPECT_EQ(written.triangles.size(), car.mesh.triangles.size());
  const cv::Mat depth = cv::imread(seq + "/gt/depth/000000_01.png", cv::IMREAD_UNCHANGED);
  const cv::Mat object_map = cv::imread(seq + "/gt/obj_map/000000_01.png", cv::IMREAD_UNCHANGED);
  const Eigen::Vector4d plane = ReadPlane(seq + "/planes/000000_01.txt");
  ASSERT_FALSE(depth.empty());
  PinholeCamera camera;
  int cars_checked = 0, cars_on_tyres = 0;
  for (int id = 1; id <= summary.num_tracks; ++id) {
    double lowest = 1e9;
    int below_body = 0, pixels = 0;
    for (int v = 0; v < depth.rows; ++v) {
      for (int u = 0; u < depth.cols; ++u) {
        if (object_map.at<uint8_t>(v, u) != id || depth.at<uint16_t>(v, u) == 0) continue;
        const Eigen::Vector3d p = camera.Ray(u, v) * (depth.at<uint16_t>(v, u) / 256.0);
        const double height = plane.head<3>().dot(p) + plane[3];  // above the road (normal up)
        lowest = std::min(lowest, height);
        if (height < wheel_options.ground_clearance - 0.04) ++below_body;
        ++pixels;
      }
    }
    if (pixels < 2000) continue;  // far or hidden: too few pixels to see the tyres
    // A car whose lower edge is hidden behind another car (in most of its image
    // columns the pixel under its lowest one is another car's) shows no tyres.
    int columns = 0, hidden_columns = 0;
    for (int u = 0; u < depth.cols; ++u) {
      int bottom = -1;
      for (int v = 0; v < depth.rows; ++v) {
        if (object_map.at<uint8_t>(v, u) == id) bottom = v;
      }
      if (bottom < 0) continue;
      ++columns;
      const int below = bottom + 1 < depth.rows ? object_map.at<uint8_t>(bottom + 1, u) : 0;
      hidden_columns += below != 0 && below != id ? 1 : 0;
    }
    if (2 * hidden_columns > columns) continue;
    ++cars_checked;
    EXPECT_GT(lowest, -0.02) << "car " << id - 1 << ": nothing below the road";
    // Seen from behind or in front, the body's overhang hides the tyres of a
    // car at 10 m or more; seen from the side or obliquely, they touch the road.
    if (lowest < 0.04 && below_body > 20) ++cars_on_tyres;
  }
  EXPECT_GE(cars_checked, 2);
  EXPECT_GE(2 * cars_on_tyres, cars_checked) << "the tyres touch the road and show under the lifted body";
  fs::remove_all(root);
}

// --near-share decides how many of a street sequence's cars lie nearer than
// 20 m at the middle frame (parked rows and traffic cars alike). With parked
// cars, the share is measured over the parked ones.
double NearShareOfCars(double near_share, const std::string& root, int parked = 0) {
  SynthOptions options = test::QuickSynthOptions(root, 23);
  options.num_sequences = 4;
  options.num_frames = 3;
  options.cars_per_sequence = parked > 0 ? 1 : 3;
  options.parked_cars_per_sequence = parked;
  options.street.intersection_probability = 0.0;  // no junction to keep rows off
  options.max_distance = 40.0;
  options.near_share = near_share;
  const SynthSummary summary = SynthesizeSequences(options, test::TwoBoxCars());
  int cars = 0, near = 0;
  for (const SynthSequenceInfo& s : summary.sequences) {
    std::ifstream in(s.folder + "/gt/cars.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    for (const nlohmann::json& car : j.at("cars")) {
      if (parked > 0 && !car.at("parked").get<bool>()) continue;
      ++cars;
      near += car.at("distance_at_middle_frame").get<double>() < 20.0 ? 1 : 0;
    }
  }
  fs::remove_all(root);
  EXPECT_GE(cars, 8);
  return cars > 0 ? double(near) / cars : 0.0;
}

TEST(Synth, NearShareSetsTheDistances) {
  EXPECT_GE(NearShareOfCars(1.0, test::MakeTempFolder("synth_near_all")), 0.75);
  EXPECT_LE(NearShareOfCars(0.0, test::MakeTempFolder("synth_near_none")), 0.25);
  const double half = NearShareOfCars(0.5, test::MakeTempFolder("synth_near_half"));
  EXPECT_GE(half, 0.3);
  EXPECT_LE(half, 0.7);
  // Parked rows (two cars per sequence, split over the parking lanes).
  EXPECT_GE(NearShareOfCars(1.0, test::MakeTempFolder("synth_near_parked_all"), 2), 0.75);
  EXPECT_LE(NearShareOfCars(0.0, test::MakeTempFolder("synth_near_parked_none"), 2), 0.25);
}

TEST(Synth, RejectsBadOptions) {
  SynthOptions options = test::QuickSynthOptions("/nonexistent/never", 1);
  options.num_frames = 0;
  EXPECT_THROW(SynthesizeSequences(options, test::TwoBoxCars()), Error);
  options = test::QuickSynthOptions("/nonexistent/never", 1);
  options.min_distance = 50.0;
  EXPECT_THROW(options.Check(), Error);
  options = test::QuickSynthOptions("/nonexistent/never", 1);
  options.window_interior_albedo = -0.1;
  EXPECT_THROW(options.Check(), Error);
  options.window_interior_albedo = 0.6;
  EXPECT_THROW(options.Check(), Error);
  options = test::QuickSynthOptions("/nonexistent/never", 1);
  options.near_share = 1.5;
  EXPECT_THROW(options.Check(), Error);
  EXPECT_THROW(SynthesizeSequences(test::QuickSynthOptions("/nonexistent/never", 1), {}), Error);
}

}  // namespace
}  // namespace samp
