// `samp calibrate-detector` as a process on a small sequence written here
// (samp's layout: calibration, detections/, ground truth): the model JSON and
// its plot beside it (a PNG OpenCV reads back, of the plot's size and not
// blank), --plot and --no-plot, detections given as a tracker's KITTI
// tracking result file (the same model as from detections/), and clear
// errors for bad output paths and a bad --dont-care-overlap
// (docs/detector_calibration.md).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "libsamp/data/detector_noise.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/sequence_layout.h"
#include "libsamp/viz/detector_noise_plot.h"
#include "tests/synth/test_scene.h"
#include "tests/tools/samp_process.h"

namespace samp {
namespace {

namespace fs = std::filesystem;
using test::LastLine;
using test::RunSamp;

// 40 frames of 5 cars at 10-60 m, detected with white noise (along the ray
// 0.2 + 0.02 d m, across 0.1 m, box 0.3 m, 5 % missed): detections/ per
// frame, the same detections as a result file RESULTS (18 columns, ids of a
// tracker that are not the cars', scores), and gt/label_02/0000.txt.
class CalibrateCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("samp_calibrate_command_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    sequence_ = (root_ / "seq").string();
    results_ = (root_ / "results.txt").string();
    for (const char* folder : {"calib", "detections", "gt/label_02"}) fs::create_directories(root_ / "seq" / folder);
    const SequenceLayout layout(sequence_, "0000");
    StereoCalibration calibration;
    calibration.baseline = 0.54;
    WriteCalibration(layout.Calibration(), calibration);
    std::mt19937 rng(3);
    std::normal_distribution<double> unit(0.0, 1.0);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::vector<ObjectLabel> truths, results;
    for (int f = 0; f < 40; ++f) {
      std::vector<ObjectLabel> detections;
      for (int c = 0; c < 5; ++c) {
        ObjectLabel truth;
        truth.frame = f, truth.track_id = c;
        truth.position = Eigen::Vector3d(-5 + 2.5 * c, 1.65, 10 + 10.0 * c + 0.25 * f);
        truth.height = 1.5, truth.width = 1.8, truth.length = 4.2;
        truth.rotation_y = -1.5;
        truths.push_back(truth);
        if (uniform(rng) < 0.05) continue;
        ObjectLabel d = truth;
        const double distance = std::hypot(truth.position.x(), truth.position.z());
        const Eigen::Vector3d ray = Eigen::Vector3d(truth.position.x(), 0, truth.position.z()) / distance;
        d.position += ray * (0.2 + 0.02 * distance) * unit(rng) + Eigen::Vector3d(ray.z(), 0, -ray.x()) * 0.1 * unit(rng);
        d.height += 0.3 * unit(rng), d.width += 0.3 * unit(rng), d.length += 0.3 * unit(rng);
        d.rotation_y += 0.05 * unit(rng);
        d.frame = -1, d.track_id = -1;
        detections.push_back(d);
        d.frame = f, d.track_id = 100 + (7 * c + f) % 9;  // the tracker's ids
        d.score = 0.9;
        results.push_back(d);
      }
      WriteLabels(layout.Detections(f), detections);
    }
    WriteTrackingLabels(layout.GroundTruthLabels(), truths);
    WriteTrackingLabels(results_, results);
  }
  void TearDown() override { fs::remove_all(root_); }

  int Run(std::vector<std::string> args, std::string* err) {
    args.insert(args.begin(), {"calibrate-detector", "--seq", sequence_, "-q"});
    return RunSamp(args, (root_ / "log").string(), err);
  }

  fs::path root_;
  std::string sequence_, results_;
};

TEST_F(CalibrateCommandTest, WritesTheModelAndItsPlot) {
  const std::string out = (root_ / "out" / "detector.json").string();
  std::string err;
  ASSERT_EQ(Run({"-o", out}, &err), 0) << err;
  const DetectorNoiseModel model = ReadDetectorNoiseModel(out);
  EXPECT_EQ(model.source, "ground truth");
  // The plot beside the JSON: a PNG of the plot's size, not blank.
  const std::string png = (root_ / "out" / "detector.png").string();
  const cv::Mat image = cv::imread(png, cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty()) << png;
  const DetectorNoisePlotOptions plot;
  EXPECT_EQ(image.cols, plot.Width());
  EXPECT_EQ(image.rows, plot.Height());
  cv::Scalar mean, deviation;
  cv::meanStdDev(image, mean, deviation);
  EXPECT_GT(deviation[0], 10.0);
  EXPECT_GT(mean[0], 180.0);  // a white background with lines and text
  // --plot FILE elsewhere; --no-plot writes none.
  const std::string elsewhere = (root_ / "plots" / "error_by_distance.png").string();
  ASSERT_EQ(Run({"-o", (root_ / "two.json").string(), "--plot", elsewhere}, &err), 0) << err;
  EXPECT_FALSE(cv::imread(elsewhere).empty());
  EXPECT_FALSE(fs::exists(root_ / "two.png"));
  ASSERT_EQ(Run({"-o", (root_ / "three.json").string(), "--no-plot"}, &err), 0) << err;
  EXPECT_TRUE(fs::exists(root_ / "three.json"));
  EXPECT_FALSE(fs::exists(root_ / "three.png"));
}

// The result file's ids are the tracker's: ignored, the detections matched by
// frame and position, so the model is the one of detections/.
TEST_F(CalibrateCommandTest, KittiTrackingResultFileGivesTheSameModel) {
  std::string err;
  ASSERT_EQ(Run({"-o", (root_ / "layout.json").string(), "--no-plot"}, &err), 0) << err;
  ASSERT_EQ(Run({"-o", (root_ / "results.json").string(), "--no-plot", "--detections", results_}, &err), 0) << err;
  EXPECT_EQ(test::ReadText((root_ / "results.json").string()), test::ReadText((root_ / "layout.json").string()));
  ASSERT_EQ(Run({"-o", (root_ / "scored.json").string(), "--no-plot", "--detections", results_,
                 "--detection-format", "kitti-tracking", "--min-score", "0.95"},
                &err),
            1);
  EXPECT_NE(LastLine(err).find("calibrate-detector: only 0 detection(s) match"), std::string::npos) << err;
  // A line of the file with a wrong column count names the file and line.
  { std::ofstream(results_, std::ios::app) << "3 1 Car 0 0 0 0 0 0 0 1.5 1.8 4.2 1 1.65 20\n"; }
  EXPECT_EQ(Run({"-o", (root_ / "bad.json").string(), "--detections", results_}, &err), 1);
  EXPECT_NE(LastLine(err).find("results.txt:"), std::string::npos) << err;
  EXPECT_NE(LastLine(err).find("16 columns, expected 17 or 18"), std::string::npos) << err;
}

TEST_F(CalibrateCommandTest, BadOutputPathsAreClearErrors) {
  std::string err;
  // The plot's folder would be inside a file.
  { std::ofstream(root_ / "a_file") << "x"; }
  const std::string inside_a_file = (root_ / "a_file" / "plot.png").string();
  EXPECT_EQ(Run({"-o", (root_ / "m.json").string(), "--plot", inside_a_file}, &err), 1);
  EXPECT_EQ(LastLine(err).rfind("samp: error: cannot create directory " + (root_ / "a_file").string(), 0), 0u) << err;
  // A folder where the plot should be.
  fs::create_directories(root_ / "taken.png");
  EXPECT_EQ(Run({"-o", (root_ / "m.json").string(), "--plot", (root_ / "taken.png").string()}, &err), 1);
  EXPECT_NE(LastLine(err).find("taken.png: it exists and is a folder"), std::string::npos) << err;
  // The default plot path would be the JSON itself.
  EXPECT_EQ(Run({"-o", (root_ / "model.png").string()}, &err), 1);
  EXPECT_NE(LastLine(err).find("would replace the model JSON"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(root_ / "model.png"));
  // --plot and --no-plot together: a usage error.
  EXPECT_EQ(Run({"-o", (root_ / "m.json").string(), "--plot", (root_ / "p.png").string(), "--no-plot"}, &err), 2);
  EXPECT_EQ(err.rfind("samp: error: ", 0), 0u) << err;
}

// --dont-care-overlap is a share in [0, 1]: another value is a usage error
// naming the option; a valid one changes nothing here (the labels have no
// DontCare boxes), and the model has no samples.dont_care_ignored.
TEST_F(CalibrateCommandTest, DontCareOverlapIsAShare) {
  std::string err;
  for (const char* bad : {"1.5", "-0.1", "half"}) {
    EXPECT_EQ(Run({"-o", (root_ / "m.json").string(), "--no-plot", "--dont-care-overlap", bad}, &err), 2) << bad;
    EXPECT_EQ(err.rfind("samp: error: ", 0), 0u) << err;
    EXPECT_NE(err.find("--dont-care-overlap"), std::string::npos) << err;
  }
  EXPECT_FALSE(fs::exists(root_ / "m.json"));
  ASSERT_EQ(Run({"-o", (root_ / "default.json").string(), "--no-plot"}, &err), 0) << err;
  ASSERT_EQ(Run({"-o", (root_ / "whole.json").string(), "--no-plot", "--dont-care-overlap", "1"}, &err), 0) << err;
  const std::string model = test::ReadText((root_ / "default.json").string());
  EXPECT_EQ(test::ReadText((root_ / "whole.json").string()), model);
  EXPECT_EQ(model.find("dont_care_ignored"), std::string::npos);
}

}  // namespace
}  // namespace samp
