#include "tests/eval/test_scene.h"

#include <filesystem>
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

std::string MakeTempFolder(const std::string& name) {
  namespace fs = std::filesystem;
  std::random_device device;
  const fs::path path = fs::temp_directory_path() /
                        ("samp_eval_" + name + "_" + std::to_string(device()));
  fs::remove_all(path);
  fs::create_directories(path);
  return path.string();
}

}  // namespace samp::test
