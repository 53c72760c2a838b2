// Evaluate's checks of its inputs (the scoring itself: end_to_end_test.cc).
#include "libsamp/eval/evaluation.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "libsamp/core/error.h"
#include "libsamp/data/kitti_io.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

// Issue 16: a --result folder without any result of the given sequences
// scored 0 % silently; it is an error naming the folder.
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

}  // namespace
}  // namespace samp
