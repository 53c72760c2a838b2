// The box convention (issue 28; docs/detector_calibration.md, "Box
// conventions"): a model trained on cars with mirrors (CAD extents include
// them) fitted to detections whose boxes exclude them (KITTI's convention).
// With the box convention estimated (samp fit --estimate-box-convention) the
// fit measures the width bias on the near cars and the fitted shapes keep
// their mirrors; without it (the default, bias 0) the detection size term
// shrinks them, so the test can fail.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>

#include "libsamp/core/json_fields.h"
#include "libsamp/core/mesh.h"
#include "libsamp/core/ply_io.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/sequence_layout.h"
#include "libsamp/model/trainer.h"
#include "libsamp/pipeline/fit_output.h"
#include "libsamp/pipeline/run_fit.h"
#include "libsamp/synth/synth.h"
#include "tests/synth/test_scene.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

// Each mirror sticks out this far beyond the body's side, m: the detected
// width is 2 kMirror = 0.3 m narrower than the car's extent (the issue's
// KITTI figure).
constexpr double kMirror = 0.15;

// A car in the canonical frame (x front, y down, z left, origin at the bottom
// centre): a body, a cabin, four wheels and two mirrors at the front of the
// cabin, sticking out sideways; its extent is width + 2 kMirror wide.
Mesh MirrorCar(double length, double width, double height) {
  const double h = 0.5 * length, w = 0.5 * width, shoulder = -0.55 * height;
  Mesh car = MakeBoxMesh(Eigen::Vector3d(-h, shoulder, -w), Eigen::Vector3d(h, -0.2, w));
  car.Append(MakeBoxMesh(Eigen::Vector3d(-0.3 * length, -height, -w + 0.1),
                         Eigen::Vector3d(0.2 * length, shoulder, w - 0.1)));
  for (double x : {-0.3 * length, 0.3 * length})
    for (double z : {-(w - 0.15), w - 0.15})
      car.Append(MakeBoxMesh(Eigen::Vector3d(x - 0.3, -0.6, z - 0.12), Eigen::Vector3d(x + 0.3, 0.0, z + 0.12)));
  const double mx = 0.2 * length;
  for (double side : {-1.0, 1.0}) {
    const double inner = side * (w - 0.05), outer = side * (w + kMirror);
    car.Append(MakeBoxMesh(Eigen::Vector3d(mx - 0.25, shoulder - 0.2, std::min(inner, outer)),
                           Eigen::Vector3d(mx, shoulder - 0.02, std::max(inner, outer))));
  }
  return car;
}

struct CarSize {
  double length, width, height;  // the body's width; the extent is width + 2 kMirror
};
const CarSize kCars[] = {{3.8, 1.60, 1.45}, {4.0, 1.75, 1.50}, {4.2, 1.65, 1.40},
                         {4.4, 1.80, 1.50}, {4.6, 1.70, 1.45}, {4.8, 1.85, 1.55}};

struct MirrorScene {
  std::string root, model;
  std::vector<std::string> sequences, names;  // each sequence's folder and its <seq>
};

// Trains a 4-component model on the six mirror cars (the real trainer: scans,
// SDFs, PCA) and renders 3 clean sequences of them, whose detections are then
// made 2 kMirror narrower (boxes without the mirrors).
const MirrorScene& Scene() {
  static const MirrorScene scene = [] {
    MirrorScene s;
    s.root = test::MakeTempFolder("box_convention");
    const fs::path cad = fs::path(s.root) / "cad";
    fs::create_directories(cad);
    std::vector<SynthCar> cars;
    for (size_t i = 0; i < std::size(kCars); ++i) {
      const Mesh mesh = MirrorCar(kCars[i].length, kCars[i].width, kCars[i].height);
      const std::string name = "mirror_car_" + std::to_string(i);
      WritePly((cad / (name + ".ply")).string(), mesh);
      cars.push_back({name, mesh});
    }
    const std::string manifest = s.root + "/manifest.json";
    std::ofstream(manifest) << R"({"defaults": {"up": "-y", "forward": "+x"}, "models": []})";
    TrainOptions train;
    train.cad_folder = cad.string();
    train.manifest_path = manifest;
    train.output_path = s.root + "/mirror_model.vdb";
    train.grid = GridSpec::CarDefault(0.1);
    train.scan.num_views = 20;
    train.scan.width = train.scan.height = 96;
    train.pca.num_components = 4;
    train.show_progress = false;
    train.num_threads = 2;
    TrainShapeModel(train);
    s.model = train.output_path;

    SynthOptions synth = test::QuickSynthOptions(s.root + "/seqs", 2017, SynthScene::kClean);
    synth.num_sequences = 3;
    synth.cars_per_sequence = 2;
    synth.parked_cars_per_sequence = 1;
    synth.num_frames = 8;
    synth.max_distance = 20.0;
    synth.detector.flip_probability = 0.0;
    for (const SynthSequenceInfo& q : SynthesizeSequences(synth, cars).sequences) {
      s.sequences.push_back(q.folder);
      s.names.push_back(q.name);
      const SequenceLayout layout(q.folder, q.name);
      for (int frame = 0; frame < synth.num_frames; ++frame) {
        const std::string path = layout.Detections(frame);
        if (!fs::exists(path)) continue;
        std::vector<ObjectLabel> boxes = ReadLabels(path);
        for (ObjectLabel& b : boxes) b.width -= 2 * kMirror;
        WriteLabels(path, boxes);
      }
    }
    return s;
  }();
  return scene;
}

// Fitted minus true width (the true extent, mirrors included) of every fitted
// car: per track the median over its frames matched to a true box (bottom
// centres within 1 m); over the tracks the median.
double MedianWidthError(const MirrorScene& scene, const std::string& out, int* num_tracks) {
  std::map<std::string, std::vector<double>> of_track;
  for (size_t i = 0; i < scene.sequences.size(); ++i) {
    const std::string& folder = scene.sequences[i];
    const std::string& name = scene.names[i];
    const std::vector<ObjectLabel> truth = ReadTrackingLabels(SequenceLayout(folder, name).GroundTruthLabels());
    for (const ObjectLabel& fit : ReadTrackingLabels(FitLabelsPath(out, name))) {
      for (const ObjectLabel& t : truth) {
        if (t.frame != fit.frame || (t.position - fit.position).norm() > 1.0) continue;
        of_track[name + "/" + std::to_string(fit.track_id)].push_back(fit.width - t.width);
        break;
      }
    }
  }
  std::vector<double> medians;
  for (auto& [track, errors] : of_track) {
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    medians.push_back(errors[errors.size() / 2]);
  }
  *num_tracks = int(medians.size());
  if (medians.empty()) return NAN;
  std::nth_element(medians.begin(), medians.begin() + medians.size() / 2, medians.end());
  return medians[medians.size() / 2];
}

RunFitOptions FitOptionsFor(const MirrorScene& scene, const std::string& out) {
  RunFitOptions o;
  o.model_path = scene.model;
  o.sequences = scene.sequences;
  o.output_dir = out;
  o.num_threads = 2;
  o.write_meshes = false;
  // 400 x 120 images have a ninth of a KITTI image's pixels: a near car has
  // ~1,000 points, not ~10,000 (the default 200 is for KITTI's size).
  o.calibration.box.min_points = 50;
  return o;
}

TEST(BoxConvention, MirrorsExcludedFromTheBoxesDoNotShrinkTheFit) {
  const MirrorScene& scene = Scene();
  ASSERT_EQ(scene.sequences.size(), 3u);

  // Self-calibration (the default) with the box convention (--estimate-box-convention):
  // the width bias is measured, about -2 kMirror.
  RunFitOptions on_options = FitOptionsFor(scene, scene.root + "/fit_on");
  on_options.calibration.estimate_box_convention = true;
  const RunFitSummary on = RunFit(on_options);
  ASSERT_TRUE(on.failure.empty()) << on.BriefReport();
  const DetectorNoiseModel& model = on.detector_model;
  ASSERT_TRUE(model.box_convention_estimated) << on.calibration_report;
  EXPECT_NEAR(model.size_bias[1], -2 * kMirror, 0.1) << on.calibration_report;
  const DetectorNoiseModel written = ReadDetectorNoiseModel(scene.root + "/fit_on/detector_model.json");
  EXPECT_TRUE(written.box_convention_estimated);
  EXPECT_EQ(written.size_bias[1], model.size_bias[1]);
  // tracks.json records the same estimate, box convention and sample counts included.
  const nlohmann::json record = ReadJsonFile(scene.root + "/fit_on/tracks.json").at("detector_model");
  EXPECT_EQ(record.at("origin"), "self-calibration");
  EXPECT_EQ(record.at("model"), ReadJsonFile(scene.root + "/fit_on/detector_model.json"));
  EXPECT_EQ(record.at("model").at("source"), "self-calibration");
  EXPECT_GT(record.at("model").at("samples").at("position").get<int>(), 0);
  EXPECT_EQ(record.at("model").at("box_convention").at("cars"), model.box_convention_tracks);
  int tracks_on = 0;
  const double error_on = MedianWidthError(scene, scene.root + "/fit_on", &tracks_on);

  // The estimate off (the default): the biases stay 0 and the detected widths pull the shapes narrower.
  RunFitOptions off_options = FitOptionsFor(scene, scene.root + "/fit_off");
  EXPECT_FALSE(off_options.calibration.estimate_box_convention);
  const RunFitSummary off = RunFit(off_options);
  ASSERT_TRUE(off.failure.empty()) << off.BriefReport();
  EXPECT_FALSE(off.detector_model.box_convention_estimated);
  int tracks_off = 0;
  const double error_off = MedianWidthError(scene, scene.root + "/fit_off", &tracks_off);

  std::cout << "fitted - true width (median over tracks): bias estimated " << error_on << " m (" << tracks_on
            << " tracks), bias 0 " << error_off << " m (" << tracks_off << " tracks); estimated width bias "
            << model.size_bias[1] << " m\n";
  // The written model given back (--detector-model): its box convention is
  // read and applied without a new estimate, so the shapes keep their mirrors.
  RunFitOptions file_options = FitOptionsFor(scene, scene.root + "/fit_file");
  file_options.detector_model_path = scene.root + "/fit_on/detector_model.json";
  const RunFitSummary from_file = RunFit(file_options);
  ASSERT_TRUE(from_file.failure.empty()) << from_file.BriefReport();
  EXPECT_EQ(from_file.detector_model.size_bias[1], model.size_bias[1]);
  int tracks_file = 0;
  const double error_file = MedianWidthError(scene, scene.root + "/fit_file", &tracks_file);
  EXPECT_LE(std::abs(error_file), 0.05) << "fitted - true width, box convention from the file";

  ASSERT_GE(tracks_on, 5);
  ASSERT_GE(tracks_off, 5);
  // Tolerance: half the model's 0.1 m voxel (the inside box's sides are the
  // SDF's zero crossings, interpolated within a voxel); the estimate's own
  // error (true -0.30 m) is within the 0.1 m checked above. Measured (GCC
  // 12): +0.013 m with the estimate, -0.092 m without; the test asks the
  // run without it to lose at least 0.06 m of the 0.30 m of mirrors (more
  // than the tolerance) and the estimate to win back at least as much.
  EXPECT_LE(std::abs(error_on), 0.05) << "fitted - true width, bias estimated (" << tracks_on << " tracks)";
  EXPECT_LE(error_off, -0.06) << "fitted - true width, bias 0 (" << tracks_off << " tracks)";
  EXPECT_GE(error_on - error_off, 0.06);
}

}  // namespace
}  // namespace samp
