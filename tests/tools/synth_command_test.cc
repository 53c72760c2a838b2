// `samp synth` as a process: --detector-profile sets the detector (explicit
// --det-* options override its fields), is recorded in config.json, and the
// profile's true noise model is written to SEQ/gt/detector_model.json; an
// unknown profile is a usage error (docs/synthetic.md, "Detector profiles").
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "libsamp/core/ply_io.h"
#include "libsamp/data/detector_noise.h"
#include "libsamp/synth/detector_model.h"
#include "tests/synth/test_scene.h"
#include "tests/tools/samp_process.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

// The arguments of a small, fast synthesis (one sequence of 2 frames, 400 x 120
// px, true-disparity noise) of the box car into `out`.
std::vector<std::string> QuickSynth(const std::string& mesh, const std::string& out) {
  return {"synth", "--car-mesh", mesh, "--preset", "clean", "--disparity", "true", "--sequences", "1",
          "--frames", "2", "--cars-per-sequence", "1", "--width", "400", "--height", "120", "--focal",
          "232.38", "--cx", "196.3", "--cy", "55.67", "--min-distance", "6", "--max-distance", "25", "-o", out,
          "-q"};
}

TEST(SynthCommand, DetectorProfileIsAppliedRecordedAndItsTrueModelWritten) {
  const std::string root = test::MakeTempFolder("synth_command_profile");
  const std::string mesh = root + "/boxcar.ply";
  WritePly(mesh, test::MakeBoxCar());
  std::string err;
  std::vector<std::string> args = QuickSynth(mesh, root + "/kitti");
  for (const char* a : {"--detector-profile", "kitti-boxes", "--det-flip", "0.01"}) args.push_back(a);
  ASSERT_EQ(test::RunSamp(args, root + "/log", &err), 0) << err;
  const nlohmann::json config = nlohmann::json::parse(test::ReadText(root + "/kitti/config.json"));
  const nlohmann::json& detector = config.at("detector");
  const DetectorModelOptions kitti = DetectorProfile("kitti-boxes");
  EXPECT_EQ(detector.at("profile"), "kitti-boxes");
  EXPECT_EQ(detector.at("width_bias").get<double>(), kitti.width_bias);
  EXPECT_EQ(detector.at("along_ray_bias").get<double>(), kitti.along_ray_bias);
  // The profile replaces the clean preset's detector; the explicit option wins over the profile.
  EXPECT_EQ(detector.at("size_sigma").get<double>(), kitti.size_sigma);
  EXPECT_EQ(detector.at("flip_probability").get<double>(), 0.01);
  const DetectorNoiseModel model = ReadDetectorNoiseModel(root + "/kitti/000000/gt/detector_model.json");
  // The width's error as the detector draws it, clipped at half the true size (synth/detector_model.h).
  EXPECT_EQ(model.size_bias[1], ClippedNormal(kitti.width_bias, kitti.size_sigma, -0.9).mean);
  EXPECT_NEAR(model.size_bias[1], kitti.width_bias, 0.005);
  EXPECT_EQ(model.along_bias, kitti.along_ray_bias);
  EXPECT_EQ(model.flip_rate, 0.01);
  EXPECT_NE(model.source.find("kitti-boxes"), std::string::npos);

  // Without a profile: the preset's detector, no profile or bias keys.
  ASSERT_EQ(test::RunSamp(QuickSynth(mesh, root + "/plain"), root + "/log", &err), 0) << err;
  const nlohmann::json plain = nlohmann::json::parse(test::ReadText(root + "/plain/config.json")).at("detector");
  EXPECT_FALSE(plain.contains("profile"));
  EXPECT_FALSE(plain.contains("width_bias"));
  EXPECT_EQ(plain.at("size_sigma").get<double>(), 0.0);  // the clean preset's
  EXPECT_TRUE(fs::exists(root + "/plain/000000/gt/detector_model.json"));

  // An unknown profile: a usage error naming the option.
  args = QuickSynth(mesh, root + "/unknown");
  for (const char* a : {"--detector-profile", "radar"}) args.push_back(a);
  EXPECT_NE(test::RunSamp(args, root + "/log", &err), 0);
  EXPECT_NE(err.find("--detector-profile"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(root + "/unknown/config.json"));
  fs::remove_all(root);
}

}  // namespace
}  // namespace samp
