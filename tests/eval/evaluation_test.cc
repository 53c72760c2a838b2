// Evaluate's checks of its inputs (the scoring itself: end_to_end_test.cc).
#include "libsamp/eval/evaluation.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "libsamp/core/error.h"
#include "libsamp/core/ply_io.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/eval/eval_inputs.h"
#include "libsamp/pipeline/fit_output.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

// A --result folder without any result of the given sequences would score
// 0 % silently: it is an error naming the folder.
TEST(Evaluate, ResultFolderWithoutResultsIsAnError) {
  const fs::path root = fs::temp_directory_path() / ("samp_evaluation_test_" + std::to_string(::getpid()));
  fs::remove_all(root);
  const fs::path seq = root / "seqs" / "000003";
  StereoCalibration calibration;
  calibration.baseline = 0.54;
  WriteCalibration((seq / "calib" / "000003.txt").string(), calibration);
  WriteLabels((seq / "detections" / "000003_00.txt").string(), {});
  const fs::path empty = root / "empty_fit";
  fs::create_directories(empty);
  const fs::path other = root / "other_fit";  // results of another sequence only
  WriteTrackingLabels((other / "label_02" / "000009.txt").string(), {});

  for (const fs::path& folder : {empty, other}) {
    EvalOptions options;
    options.sequences = {seq.string()};
    options.output_folder = (root / "eval").string();
    options.results = {{"full", folder.string()}};
    try {
      Evaluate(options);
      ADD_FAILURE() << "no error for " << folder;
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("result folder " + folder.string() + " (full) has no results"), std::string::npos)
          << message;
      EXPECT_NE(message.find("000003"), std::string::npos) << message;
    }
  }
  EXPECT_FALSE(fs::exists(root / "eval" / "results.md"));
  fs::remove_all(root);
}

// A result folder is read through the fit output's layout (pipeline/fit_output.h):
// its labels in label_02/<seq>.txt, or in <seq>/label_02/<seq>.txt below it; a
// track's mesh in meshes/<seq>/track_<id>.ply or meshes/track_<id>.ply.
TEST(EvalInputs, ResultFolderFollowsTheFitOutputLayout) {
  const fs::path root = fs::temp_directory_path() / ("samp_eval_inputs_test_" + std::to_string(::getpid()));
  fs::remove_all(root);
  const std::string one = (root / "one").string(), several = (root / "several").string();
  WriteTrackingLabels(FitLabelsPath(one, "000001"), {});
  WriteTrackingLabels(FitLabelsPath((root / "several" / "000002").string(), "000002"), {});
  EXPECT_EQ(eval::ResultFolder(one, "000001"), one);
  EXPECT_EQ(eval::ResultFolder(several, "000002"), (root / "several" / "000002").string());
  EXPECT_EQ(eval::ResultFolder(one, "000002"), "");

  const Mesh box = MakeBoxMesh(Eigen::Vector3d(-2, -1.5, -1), Eigen::Vector3d(2, 0, 1));
  const Mesh small = MakeBoxMesh(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 0, 1));
  WritePly((fs::path(one) / (FitMeshStem("000001", 3, true) + ".ply")).string(), box);
  WritePly((fs::path(one) / (FitMeshStem("000001", 4, false) + ".ply")).string(), small);
  eval::ResultMeshes meshes(one);
  meshes.Load("000001", 3, 0);
  meshes.Load("000001", 4, 5);
  meshes.Finish();
  EXPECT_NEAR(meshes.Get("000001", 3, 0).Bounds().Size().x(), 4.0, 1e-6);
  EXPECT_NEAR(meshes.Get("000001", 4, 5).Bounds().Size().x(), 2.0, 1e-6);
  try {
    meshes.Load("000001", 5, 0);
    ADD_FAILURE() << "no error for a track without a mesh";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no mesh for track 5 of 000001 in " + one), std::string::npos) << e.what();
  }
  fs::remove_all(root);
}

}  // namespace
}  // namespace samp
