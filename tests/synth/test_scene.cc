#include "tests/synth/test_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <random>

namespace samp::test {

Mesh MakeBoxCar(double length) {
  const double h = 0.5 * length;
  Mesh body = MakeBoxMesh(Eigen::Vector3d(-h, -0.85, -0.85), Eigen::Vector3d(h, -0.15, 0.85));
  body.Append(MakeBoxMesh(Eigen::Vector3d(-0.3 * length, -1.45, -0.75),
                          Eigen::Vector3d(0.2 * length, -0.85, 0.75)));
  // Four wheels reaching the ground.
  for (double x : {-0.3 * length, 0.3 * length}) {
    for (double z : {-0.7, 0.7}) {
      body.Append(MakeBoxMesh(Eigen::Vector3d(x - 0.3, -0.6, z - 0.12), Eigen::Vector3d(x + 0.3, 0.0, z + 0.12)));
    }
  }
  return body;
}

std::vector<SynthCar> TwoBoxCars() { return {{"boxcar_a", MakeBoxCar(4.2)}, {"boxcar_b", MakeBoxCar(3.8)}}; }

SynthOptions QuickSynthOptions(const std::string& output_folder, uint64_t seed, SynthScene scene) {
  SynthOptions o = scene == SynthScene::kClean ? SynthOptions::Clean() : SynthOptions();
  o.parked_cars_per_sequence = 1;
  o.output_folder = output_folder;
  o.seed = seed;
  o.num_sequences = 2;
  o.cars_per_sequence = 2;
  o.num_frames = 5;
  o.width = 400;
  o.height = 120;
  o.focal_px = 721.5377 * 400.0 / 1242.0;
  o.cx_px = 609.5593 * 400.0 / 1242.0;
  o.cy_px = 172.854 * 400.0 / 1242.0;
  o.min_distance = 6.0;
  o.max_distance = 25.0;
  o.disparity = DisparitySource::kTrueWithNoise;
  o.show_progress = false;
  return o;
}

namespace {

// Signed distance to the box [lo, hi].
double BoxSdf(const Eigen::Vector3d& p, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const Eigen::Vector3d c = 0.5 * (lo + hi), h = 0.5 * (hi - lo);
  const Eigen::Vector3d q = (p - c).cwiseAbs() - h;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

Eigen::VectorXf BoxCarSdf(const GridSpec& grid, double length, double height) {
  Eigen::VectorXf values(grid.NumVoxels());
  for (int k = 0; k < grid.dims.z(); ++k) {
    for (int j = 0; j < grid.dims.y(); ++j) {
      for (int i = 0; i < grid.dims.x(); ++i) {
        values[grid.Index(i, j, k)] = float(BoxSdf(grid.Position(i, j, k),
                                                   Eigen::Vector3d(-0.5 * length, -height, -0.85),
                                                   Eigen::Vector3d(0.5 * length, 0.0, 0.85)));
      }
    }
  }
  return values;
}

}  // namespace

ShapeModel MakeBoxModel() {
  ShapeModel model;
  model.grid = GridSpec::CarDefault(0.1);
  model.mean = BoxCarSdf(model.grid, 4.0, 1.45);
  Eigen::VectorXf d_length = BoxCarSdf(model.grid, 4.2, 1.45) - model.mean;
  Eigen::VectorXf d_height = BoxCarSdf(model.grid, 4.0, 1.6) - model.mean;
  const double length_norm = d_length.norm();
  d_length /= float(length_norm);
  d_height -= d_length * d_length.dot(d_height);
  const double height_norm = d_height.norm();
  d_height /= float(height_norm);
  model.components.resize(model.mean.size(), 2);
  model.components.col(0) = d_length;
  model.components.col(1) = d_height;
  // Std. dev. of 0.3 m in length and 0.1 m in height, in code units.
  model.eigenvalues = Eigen::Vector2d(std::pow(length_norm * 0.3 / 0.2, 2), std::pow(height_norm * 0.1 / 0.15, 2));
  model.training_shapes = {"box_a", "box_b", "box_c"};
  return model;
}

std::string MakeTempFolder(const std::string& name) {
  namespace fs = std::filesystem;
  std::random_device device;
  const fs::path path = fs::temp_directory_path() /
                        ("samp_eval_" + name + "_" + std::to_string(device()));
  fs::remove_all(path);
  fs::create_directories(path);
  return path.string();
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

BoxCarScene::BoxCarScene(const std::string& name, uint64_t seed, int num_sequences, int num_frames) {
  root = MakeTempFolder(name);
  SynthOptions synth = QuickSynthOptions(root + "/seqs", seed, SynthScene::kClean);
  synth.num_sequences = num_sequences;
  synth.num_frames = num_frames;
  synth.detector.flip_probability = 0.0;
  for (const SynthSequenceInfo& q : SynthesizeSequences(synth, {{"boxcar", MakeBoxCar(4.2)}}).sequences) {
    sequences.push_back(q.folder);
    names.push_back(q.name);
  }
  model = root + "/box_model.vdb";
  MakeBoxModel().Save(model);
}

std::string BoxCarScene::Folder(const std::string& name) const {
  const std::filesystem::path folder = std::filesystem::path(root) / name;
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  return folder.string();
}

BoxCarScene::~BoxCarScene() {
  if (!root.empty() && ::testing::UnitTest::GetInstance()->Passed()) {
    std::error_code ignored;
    std::filesystem::remove_all(root, ignored);
  }
}

}  // namespace samp::test
