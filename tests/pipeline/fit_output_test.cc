// Outputs of a fit: KITTI result lines in each frame's camera, aligned
// observations, the fitted surface and the JSON record.
#include "libsamp/pipeline/fit_output.h"

#include <gtest/gtest.h>
#include <iterator>
#include <fstream>

#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/pipeline/fit_config.h"
#include "tests/fit/fit_test_util.h"
#include "tests/testing/expect_error.h"

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
}

using test::ErrorOf;

std::string TempFile(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("samp_fit_output_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

// The car grid spans x [-3, 3], y [-2.3, 0.5], z [-1.4, 1.4] m: a box within
// half a voxel (0.05 m) of a face reaches the limit along that axis.
TEST(FitOutput, GridLimitsReached) {
  const GridSpec grid = GridSpec::CarDefault();
  AlignedBox box;
  EXPECT_TRUE(GridLimitsReached(box, grid).empty());  // empty box
  box.min = Eigen::Vector3d(-2.2, -1.5, -0.9);
  box.max = Eigen::Vector3d(2.2, 0.0, 0.9);
  EXPECT_TRUE(GridLimitsReached(box, grid).empty());
  box.max.x() = 2.94;  // 0.06 m short of the face
  EXPECT_TRUE(GridLimitsReached(box, grid).empty());
  box.max.x() = 2.96;
  EXPECT_EQ(GridLimitsReached(box, grid), (std::vector<std::string>{"length"}));
  box.max.x() = 2.2;
  box.min.y() = -2.3;  // the roof at the grid's top
  box.min.z() = -1.4;  // a side at the grid's
  EXPECT_EQ(GridLimitsReached(box, grid), (std::vector<std::string>{"height", "width"}));
  box.min = Eigen::Vector3d(-2.2, -1.5, -0.9);
  box.max.y() = 0.5;  // inside below the road, to the grid's bottom
  EXPECT_EQ(GridLimitsReached(box, grid), (std::vector<std::string>{"height"}));
}

TEST(FitOutput, TracksFileRoundTripAndMissingKeys) {
  Track track;
  TracksFileTrack t;
  MakeFit(&track, &t.fit);
  t.fit.sequence = "000001";
  t.fit.frames[1].motion_model = "arc";
  t.fit.summary.solves.resize(1);
  t.fit.summary.solves[0].termination = "CONVERGENCE";
  t.fit.summary.final_cost = 1.5;
  t.box = FittedBox(Lookup(), t.fit.shape_code);
  t.mesh = "meshes/track_7.ply";
  t.points = "meshes/track_7_points.ply";
  t.at_grid_limit = {"length", "height"};
  TracksFile file;
  file.model = "model.vdb";
  TracksFileSequence sequence;
  sequence.directory = "seq/000001";
  sequence.name = "000001";
  sequence.ok = true;
  sequence.input = "sequence 000001: 2 frames";
  sequence.input_messages = {"a note"};
  sequence.tracks = {t};
  sequence.failed_tracks = {"track 3: too short"};
  file.sequences = {sequence, TracksFileSequence()};
  file.sequences[1].name = "000002";
  file.sequences[1].error = "no calib/";
  const std::string path = TempFile("tracks.json");
  WriteTracksFile(path, file);

  const TracksFile read = ReadTracksFile(path);
  EXPECT_EQ(read.model, "model.vdb");
  ASSERT_EQ(read.sequences.size(), 2u);
  EXPECT_FALSE(read.sequences[1].ok);
  EXPECT_EQ(read.sequences[1].error, "no calib/");
  const TracksFileSequence& r = read.sequences[0];
  EXPECT_TRUE(r.ok);
  EXPECT_EQ(r.input_messages, sequence.input_messages);
  EXPECT_EQ(r.failed_tracks, sequence.failed_tracks);
  ASSERT_EQ(r.tracks.size(), 1u);
  const TracksFileTrack& rt = r.tracks[0];
  EXPECT_EQ(rt.mesh, t.mesh);
  EXPECT_EQ(rt.points, t.points);
  EXPECT_EQ(rt.box.min, t.box.min);
  EXPECT_EQ(rt.box.max, t.box.max);
  EXPECT_EQ(rt.at_grid_limit, t.at_grid_limit);
  EXPECT_EQ(rt.fit.track_id, 7);
  EXPECT_EQ(rt.fit.shape_code, t.fit.shape_code);
  EXPECT_DOUBLE_EQ(rt.fit.summary.final_cost, 1.5);
  ASSERT_EQ(rt.fit.summary.solves.size(), 1u);
  EXPECT_EQ(rt.fit.summary.solves[0].termination, "CONVERGENCE");
  ASSERT_EQ(rt.fit.frames.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(rt.fit.frames[k].frame, t.fit.frames[k].frame);
    EXPECT_EQ(rt.fit.frames[k].position, t.fit.frames[k].position);
    EXPECT_EQ(rt.fit.frames[k].yaw, t.fit.frames[k].yaw);
    EXPECT_EQ(rt.fit.frames[k].motion_model, t.fit.frames[k].motion_model);
    EXPECT_TRUE(rt.fit.frames[k].points_in_world.empty());
  }

  // A missing key is an error naming the file and the key.
  nlohmann::json j = ReadJsonFile(path);
  j["sequences"][0]["tracks"][0]["frames"][1].erase("yaw");
  WriteTextFileAtomically(path, j.dump());
  const std::string message = ErrorOf([&] { ReadTracksFile(path); });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("sequences[0].tracks[0].frames[1]"), std::string::npos) << message;
  EXPECT_NE(message.find("'yaw'"), std::string::npos) << message;
}

// tracks.json's "detector_model": how the run got its detector model and the
// model itself in the format of OUT/detector_model.json (its one writer),
// sample counts included; "none" with the reason; absent in files of a samp
// before the key; a bad origin or model names the file and the key.
TEST(FitOutput, TracksFileRecordsTheDetectorModel) {
  DetectorNoiseModel model;
  model.source = "self-calibration";
  model.along_sigma_a = 0.31;
  model.size_sigma[2] = 0.45;
  model.num_position_samples = 120, model.num_size_samples = 118, model.num_yaw_samples = 117;
  model.num_tracks = 6, model.num_frames = 40;
  DistanceBin bin;
  bin.max_distance = 10.0;
  bin.count = 50;
  bin.along_sigma = bin.across_sigma = bin.vertical_sigma = 0.2;
  model.bins = {bin};
  model.notes = {"yaw: a note"};
  const std::string path = TempFile("detector_tracks.json");

  // Not recorded: no key, and a file without it reads.
  TracksFile file;
  file.model = "model.vdb";
  WriteTracksFile(path, file);
  EXPECT_FALSE(ReadJsonFile(path).contains("detector_model"));
  EXPECT_EQ(ReadTracksFile(path).detector_model.origin, "");

  // Self-calibration: the model object is what WriteDetectorNoiseModel writes.
  file.detector_model.origin = "self-calibration";
  file.detector_model.model = model;
  WriteTracksFile(path, file);
  const nlohmann::json written = ReadJsonFile(path).at("detector_model");
  EXPECT_EQ(written.at("origin"), "self-calibration");
  EXPECT_FALSE(written.contains("file"));
  EXPECT_FALSE(written.contains("reason"));
  const std::string model_file = TempFile("detector_model.json");
  WriteDetectorNoiseModel(model_file, model);
  EXPECT_EQ(written.at("model"), ReadJsonFile(model_file));
  EXPECT_EQ(written.at("model").at("samples").at("position"), 120);
  EXPECT_EQ(written.at("model").at("samples").at("tracks"), 6);
  TracksFileDetectorModel read = ReadTracksFile(path).detector_model;
  EXPECT_EQ(read.origin, "self-calibration");
  EXPECT_EQ(read.model.ToJson(), model.ToJson());

  // A model file: its path too.
  file.detector_model.origin = "file";
  file.detector_model.file = "calibrated/detector.json";
  WriteTracksFile(path, file);
  read = ReadTracksFile(path).detector_model;
  EXPECT_EQ(read.origin, "file");
  EXPECT_EQ(read.file, "calibrated/detector.json");
  EXPECT_EQ(read.model.ToJson(), model.ToJson());

  // None: the reason, no model.
  file.detector_model = TracksFileDetectorModel();
  file.detector_model.origin = "none";
  file.detector_model.reason = "self-calibration off";
  WriteTracksFile(path, file);
  EXPECT_FALSE(ReadJsonFile(path).at("detector_model").contains("model"));
  read = ReadTracksFile(path).detector_model;
  EXPECT_EQ(read.origin, "none");
  EXPECT_EQ(read.reason, "self-calibration off");

  file.detector_model.origin = "guessed";
  EXPECT_NE(ErrorOf([&] { WriteTracksFile(path, file); }).find("guessed"), std::string::npos);

  // Bad files: the origin, and the model checked as a detector model file is.
  nlohmann::json j = ReadJsonFile(path);
  j["detector_model"]["origin"] = "guessed";
  WriteTextFileAtomically(path, j.dump());
  std::string message = ErrorOf([&] { ReadTracksFile(path); });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("detector_model: key 'origin'"), std::string::npos) << message;
  j["detector_model"] = {{"origin", "self-calibration"}, {"model", ReadJsonFile(model_file)}};
  j["detector_model"]["model"].erase("samples");
  WriteTextFileAtomically(path, j.dump());
  message = ErrorOf([&] { ReadTracksFile(path); });
  EXPECT_NE(message.find(path + ": detector_model.model"), std::string::npos) << message;
  EXPECT_NE(message.find("'samples'"), std::string::npos) << message;
}

// Bytes that are not UTF-8 in a sequence folder or calibration name (a
// Latin-1 name) are written as U+FFFD: tracks.json and config.json once threw
// json type_error 316 at the last step (issue 32).
TEST(FitOutput, NonUtf8NamesAreWrittenAsReplacementCharacters) {
  TracksFile file;
  file.model = "model\xff.vdb";
  TracksFileSequence sequence;
  sequence.directory = "seq/caf\xe9";
  sequence.name = "caf\xe9";
  sequence.ok = false;
  sequence.error = "calib/caf\xe9.txt: cannot open";
  file.sequences.push_back(sequence);
  const std::string tracks = TempFile("latin1_tracks.json");
  WriteTracksFile(tracks, file);
  std::ifstream in(tracks, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("caf\xef\xbf\xbd"), std::string::npos) << text;
  EXPECT_EQ(text.find('\xe9'), std::string::npos);

  FitConfig config;
  config.options.model_path = "model\xff.vdb";
  config.options.sequences = {"seq/caf\xe9"};
  config.options.output_dir = "out";
  const std::string path = TempFile("latin1_config.json");
  WriteFitConfig(path, config);
  std::ifstream config_in(path, std::ios::binary);
  const std::string config_text((std::istreambuf_iterator<char>(config_in)), std::istreambuf_iterator<char>());
  EXPECT_NE(config_text.find("seq/caf\xef\xbf\xbd"), std::string::npos) << config_text;
}

TEST(FitOutput, ConfigHoldsEveryOptionAndReadsBack) {
  FitConfig config;
  config.options.model_path = "model.vdb";
  config.options.sequences = {"a", "b"};
  config.options.output_dir = "out";
  config.options.num_threads = 3;
  config.options.fit.data_term = DataTerm::kDisparity;
  config.options.fit.data_weighting = DataWeighting::kMean;
  config.options.link_only = true;
  config.options.fit.motion_noise.sigma_yaw = 0.07;
  config.options.sequence.stereo.block_size = 7;
  config.options.sequence.road_plane.seed = 42;
  config.options.sequence.tracker.min_track_length = 1;
  config.model_components = 5;
  const std::string path = TempFile("config.json");
  WriteFitConfig(path, config);
  const nlohmann::json j = ReadJsonFile(path);
  // The options that change a result when disparity/ or planes/ are missing are there.
  EXPECT_EQ(j["sequence"]["stereo"]["block_size"], 7);
  EXPECT_EQ(j["sequence"]["road_plane"]["seed"], 42);
  EXPECT_EQ(j["fit"]["em_iterations"], 1);
  EXPECT_EQ(j["fit"]["linear_solver"], "sparse_normal_cholesky");
  EXPECT_EQ(j["fit"]["data_term"], "disparity");
  EXPECT_EQ(j["fit"]["data_weighting"], "mean");

  const FitConfig read = ReadFitConfig(path);
  EXPECT_EQ(read.model_components, 5);
  EXPECT_EQ(read.options.sequences, config.options.sequences);
  EXPECT_EQ(read.options.num_threads, 3);
  EXPECT_EQ(read.options.fit.data_term, DataTerm::kDisparity);
  EXPECT_EQ(read.options.fit.data_weighting, DataWeighting::kMean);
  EXPECT_TRUE(read.options.link_only);
  EXPECT_EQ(read.options.fit.motion_noise.sigma_yaw, 0.07);
  EXPECT_EQ(read.options.sequence.stereo.block_size, 7);
  EXPECT_EQ(read.options.sequence.road_plane.seed, 42u);
  EXPECT_EQ(read.options.sequence.tracker.min_track_length, 1);
  EXPECT_TRUE(read.detector_model.origin.empty());  // none given: no key
  EXPECT_FALSE(j.contains("detector_model_used"));
  // Writing what was read gives the same file.
  WriteFitConfig(path + ".2", read);
  EXPECT_EQ(ReadJsonFile(path + ".2"), j);

  // The run's detector model, as tracks.json records it, reads back.
  FitConfig with_model = config;
  with_model.detector_model.origin = "self-calibration";
  with_model.detector_model.model.size_sigma[1] = 0.42;
  with_model.detector_model.model.num_frames = 17;
  WriteFitConfig(path + ".3", with_model);
  const FitConfig read_model = ReadFitConfig(path + ".3");
  EXPECT_EQ(read_model.detector_model.origin, "self-calibration");
  EXPECT_EQ(read_model.detector_model.model.ToJson(), with_model.detector_model.model.ToJson());
  EXPECT_EQ(ReadJsonFile(path + ".3").at("detector_model_used"),
            DetectorModelRecordToJson(with_model.detector_model, path + ".3"));

  nlohmann::json broken = j;
  broken["sequence"]["road_plane"].erase("max_tilt_deg");
  WriteTextFileAtomically(path, broken.dump());
  const std::string message = ErrorOf([&] { ReadFitConfig(path); });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("sequence.road_plane"), std::string::npos) << message;
  EXPECT_NE(message.find("'max_tilt_deg'"), std::string::npos) << message;

  nlohmann::json unknown = j;
  unknown["fit"]["data_term"] = "no-such-term";
  WriteTextFileAtomically(path, unknown.dump());
  const std::string unknown_message = ErrorOf([&] { ReadFitConfig(path); });
  EXPECT_NE(unknown_message.find(path), std::string::npos) << unknown_message;
  EXPECT_NE(unknown_message.find("'data_term'"), std::string::npos) << unknown_message;
}

}  // namespace
}  // namespace samp
