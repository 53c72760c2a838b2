// `samp fit` as a process on small synthetic sequences: exit status and the
// one-line error when every track failed or two sequences share a name, the
// detector model's plot, and SIGINT in the middle of a run
// (docs/reliability.md, "Text, JSON and outputs").
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <thread>

#include "libsamp/data/kitti_io.h"
#include "libsamp/synth/synth.h"
#include "libsamp/viz/detector_noise_plot.h"
#include "tests/synth/test_scene.h"
#include "tests/tools/samp_process.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

// Two sequences of 4 frames (clean preset) and the box model.
const test::BoxCarScene& TheScene() {
  static const test::BoxCarScene scene("fit_command", 11, 2, 4);
  return scene;
}

using test::LastLine;
using test::RunSamp;
using test::StartSamp;

// Every track fails (an association radius that takes no stereo point: each
// track is refused by the fitter; tests/pipeline
// RunFit.UnusableSolveIsAFailedTrack makes every solve fail in Ceres instead,
// which no command-line option can): exit status 1 with one error line, and
// the run's record is still written.
TEST(FitCommand, EveryTrackFailedExitsOne) {
  const test::BoxCarScene& scene = TheScene();
  const std::string runs = TheScene().Folder("every_track_failed");
  const std::string out = runs + "/out";
  std::string err;
  const int status = RunSamp({"fit", "--model", scene.model, "--seq", scene.sequences[0], "--out", out,
                              "--association-radius", "1e-9", "-q"},
                             runs + "/log", &err);
  EXPECT_EQ(status, 1) << err;
  const std::string last = LastLine(err);
  EXPECT_EQ(last.rfind("samp: error: no track was fitted although the input had ", 0), 0u) << err;
  EXPECT_NE(last.find("every track failed"), std::string::npos) << err;
  EXPECT_TRUE(fs::exists(out + "/tracks.json"));
  EXPECT_TRUE(ReadTrackingLabels(out + "/label_02/" + scene.names[0] + ".txt").empty());
  EXPECT_FALSE(fs::exists(out + "/meshes"));

  // The same with the default radius exits 0 (the failure is that option's).
  ASSERT_EQ(RunSamp({"fit", "--model", scene.model, "--seq", scene.sequences[0], "--out", out, "-q"}, runs + "/log",
                    &err),
            0)
      << err;
  EXPECT_FALSE(ReadTrackingLabels(out + "/label_02/" + scene.names[0] + ".txt").empty());
}

// The options come from the option tables (fit/fit_option_table.h,
// data/tracker_option_table.h): new names, deprecated old names (which print a
// note) and nested ones reach config.json; a value that breaks its rule is
// refused while parsing, naming the option; --help-options prints the table.
TEST(FitCommand, TableOptionsAndDeprecatedNames) {
  const test::BoxCarScene& scene = TheScene();
  const std::string runs = TheScene().Folder("table_options");
  const std::string out = runs + "/out";
  std::string err;
  ASSERT_EQ(RunSamp({"fit", "--seq", scene.sequences[0], "--out", out, "--link-only", "--weighting", "mean",
                     "--huber", "2", "--ray-depth-inside", "--tracker-gate", "10", "--no-tracker-swaps",
                     "--motion-sigma-yaw", "0.04", "--em-box-margin", "0.5", "--tracker-along-sigma", "0.1,0,0.001"},
                    runs + "/log", &err),
            0)
      << err;
  for (const char* note : {"--weighting is deprecated, use --data-weighting",
                           "--huber is deprecated, use --huber-threshold",
                           "--ray-depth-inside is deprecated, use --data-term ray-depth",
                           "--tracker-gate is deprecated, use --tracker-gate-chi2",
                           "--no-tracker-swaps is deprecated, use --no-tracker-resolve-switches"}) {
    EXPECT_NE(err.find(note), std::string::npos) << note << " not in: " << err;
  }
  const nlohmann::json config = nlohmann::json::parse(test::ReadText(out + "/config.json"));
  EXPECT_EQ(config["fit"]["data_weighting"], "mean");
  EXPECT_EQ(config["fit"]["huber_threshold"], 2.0);
  EXPECT_EQ(config["fit"]["data_term"], "ray-depth");
  EXPECT_EQ(config["fit"]["em_box_margin"], 0.5);
  EXPECT_EQ(config["fit"]["motion_noise"]["sigma_yaw"], 0.04);
  const nlohmann::json& tracker = config["sequence"]["tracker"];
  EXPECT_EQ(tracker["gate_chi2"], 10.0);
  EXPECT_EQ(tracker["resolve_switches"], false);
  EXPECT_EQ(tracker["along_sigma_a"], 0.1);
  EXPECT_EQ(tracker["along_sigma_c"], 0.001);

  EXPECT_NE(RunSamp({"fit", "--seq", scene.sequences[0], "--out", out, "--link-only", "--em-iterations", "-1"},
                    runs + "/log", &err),
            0);
  EXPECT_NE(err.find("--em-iterations"), std::string::npos) << err;
  EXPECT_NE(err.find("must be >= 0, got -1"), std::string::npos) << err;

  EXPECT_EQ(RunSamp({"fit", "--help-options", "markdown"}, runs + "/help", &err), 0) << err;
  const std::string table = test::ReadText(runs + "/help.out");
  EXPECT_EQ(table.rfind("| option | command line | default | rule | meaning |\n", 0), 0u) << table;
  EXPECT_NE(table.find("| em_iterations | `--em-iterations` | 1 | >= 0 |"), std::string::npos) << table;
}

// The plot of `samp calibrate-detector` (viz/detector_noise_plot.h) is read
// back from `path`: a PNG of the plot's size.
void ExpectDetectorModelPlot(const std::string& path) {
  const std::string bytes = test::ReadText(path);
  ASSERT_GT(bytes.size(), 8u) << path;
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << path;
  const cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty()) << path;
  const DetectorNoisePlotOptions plot;
  EXPECT_EQ(image.cols, plot.Width());
  EXPECT_EQ(image.rows, plot.Height());
}

// OUT/detector_model.png beside OUT/detector_model.json: the run's detector
// model drawn as `samp calibrate-detector` draws it, self-calibrated (the
// default) or read with --detector-model. --no-detector-plot writes none, and
// config.json records the option only then.
TEST(FitCommand, DetectorModelPlotBesideItsJson) {
  const test::BoxCarScene& scene = TheScene();
  const std::string runs = TheScene().Folder("detector_plot");
  const std::string out = runs + "/out";
  std::string err;
  ASSERT_EQ(RunSamp({"fit", "--model", scene.model, "--seq", scene.sequences[0], "--out", out, "-q"}, runs + "/log",
                    &err),
            0)
      << err;
  ASSERT_TRUE(fs::exists(out + "/detector_model.json"));
  ExpectDetectorModelPlot(out + "/detector_model.png");
  EXPECT_FALSE(nlohmann::json::parse(test::ReadText(out + "/config.json")).contains("detector_plot"));

  // A model read from a file is drawn too.
  fs::copy_file(out + "/detector_model.json", runs + "/model.json", fs::copy_options::overwrite_existing);
  const std::string from_file = runs + "/from_file";
  ASSERT_EQ(RunSamp({"fit", "--seq", scene.sequences[0], "--out", from_file, "--link-only", "--detector-model",
                     runs + "/model.json", "-q"},
                    runs + "/log", &err),
            0)
      << err;
  ExpectDetectorModelPlot(from_file + "/detector_model.png");

  // --no-detector-plot: the model's JSON without its plot (replacing the earlier run).
  ASSERT_EQ(RunSamp({"fit", "--seq", scene.sequences[0], "--out", out, "--link-only", "--no-detector-plot", "-q"},
                    runs + "/log", &err),
            0)
      << err;
  EXPECT_TRUE(fs::exists(out + "/detector_model.json"));
  EXPECT_FALSE(fs::exists(out + "/detector_model.png"));
  EXPECT_EQ(nlohmann::json::parse(test::ReadText(out + "/config.json")).at("detector_plot"), false);
}

// A batch where one sequence fails exits 1 (everything asked for was not
// written) and leaves an earlier good output byte-identical.
TEST(FitCommand, BatchWithAFailedSequenceExitsOneAndKeepsTheEarlierOutput) {
  const test::BoxCarScene& scene = TheScene();
  const std::string runs = TheScene().Folder("batch_failed");
  const std::string out = runs + "/out";
  std::string err;
  ASSERT_EQ(RunSamp({"fit", "--model", scene.model, "--seq", scene.sequences[0], "--out", out, "-q"}, runs + "/log",
                    &err),
            0)
      << err;
  const std::string labels = test::ReadText(out + "/label_02/" + scene.names[0] + ".txt");
  const std::string tracks = test::ReadText(out + "/tracks.json");
  const std::string missing = runs + "/no_such_sequence";
  const int status = RunSamp({"fit", "--model", scene.model, "--seq", scene.sequences[0], "--seq", missing, "--out",
                              out, "-q"},
                             runs + "/log", &err);
  EXPECT_EQ(status, 1) << err;
  const std::string last = LastLine(err);
  EXPECT_EQ(last.rfind("samp: error: 1 of 2 sequences failed: " + missing, 0), 0u) << err;
  EXPECT_NE(last.find("keeps the earlier run's output"), std::string::npos) << err;
  EXPECT_EQ(test::ReadText(out + "/label_02/" + scene.names[0] + ".txt"), labels);
  EXPECT_EQ(test::ReadText(out + "/tracks.json"), tracks);
}

// Usage errors (CLI11's parse errors, which exited 105/106/109 without a
// samp line) exit 2 with one `samp: error: ...` line; --help and --version 0.
TEST(FitCommand, UsageErrorsExitTwoWithASampErrorLine) {
  const std::string runs = TheScene().Folder("usage");
  const std::vector<std::vector<std::string>> usage_errors = {
      {},                                               // no command
      {"no-such-command"},                              // unknown command
      {"fit", "--no-such-option"},                      // unknown option (exited 109)
      {"fit", "--seq"},                                 // option without its value
      {"fit", "--seq", runs, "--out", runs + "/o", "--threads", "many"},  // not a number (105)
      {"train", "--components", "3"},                   // required argument missing (106)
      {"eval", "--no-such-option", "1"},
  };
  for (const std::vector<std::string>& args : usage_errors) {
    std::string err;
    std::string joined;
    for (const std::string& a : args) joined += " " + a;
    EXPECT_EQ(RunSamp(args, runs + "/log", &err), 2) << "samp" << joined << "\n" << err;
    EXPECT_EQ(err.rfind("samp: error: ", 0), 0u) << "samp" << joined << "\n" << err;
  }
  std::string err;
  EXPECT_EQ(RunSamp({"--help"}, runs + "/log", &err), 0) << err;
  EXPECT_EQ(RunSamp({"fit", "--help"}, runs + "/log", &err), 0) << err;
  EXPECT_EQ(RunSamp({"--version"}, runs + "/log", &err), 0) << err;
  // An input that does not read is 1, not 2.
  { std::ofstream(runs + "/garbage.vdb") << "not a model"; }
  EXPECT_EQ(RunSamp({"inspect", runs + "/garbage.vdb"}, runs + "/log", &err), 1) << err;
  EXPECT_EQ(err.rfind("samp: error: ", 0), 0u) << err;
}

TEST(FitCommand, SameNamedSequencesExitOneBeforeFitting) {
  const test::BoxCarScene& scene = TheScene();
  const std::string runs = TheScene().Folder("same_name");
  const std::string a = runs + "/a/" + scene.names[0], b = runs + "/b/" + scene.names[0];
  fs::create_directories(runs + "/a");
  fs::create_directories(runs + "/b");
  fs::copy(scene.sequences[0], a, fs::copy_options::recursive);
  fs::copy(scene.sequences[0], b, fs::copy_options::recursive);
  const std::string out = runs + "/out";
  std::string err;
  EXPECT_EQ(RunSamp({"fit", "--model", scene.model, "--seq", a, "--seq", b, "--out", out}, runs + "/log", &err), 1)
      << err;
  // One line: the error, naming both paths; nothing fitted, nothing written.
  EXPECT_EQ(err, "samp: error: sequences " + a + " and " + b + " have the same name '" + scene.names[0] +
                     "': their outputs (label_02/" + scene.names[0] + ".txt, meshes/" + scene.names[0] +
                     "/) would overwrite each other; fit them into separate output folders\n");
  EXPECT_FALSE(fs::exists(out));
}

// KITTI tracking's own layout through the command line (issue 31): a
// sequence whose oxts file misses a frame's line, or whose detection file has
// a line with too few columns, fails with the file and line and writes no
// labels; the other sequence is fitted; exit status 1.
TEST(FitCommand, KittiTrackingBadInputNamesFileAndLineAndWritesNothingForIt) {
  const test::BoxCarScene& scene = TheScene();
  const std::string runs = TheScene().Folder("kitti_bad_input");
  SynthOptions synth = test::QuickSynthOptions(runs + "/kitti", 13, SynthScene::kClean);
  synth.num_sequences = 2;
  synth.num_frames = 4;
  synth.layout = SynthLayout::kKittiTracking;
  SynthesizeSequences(synth, {{"boxcar", test::MakeBoxCar(4.2)}});
  const std::string root = runs + "/kitti/training";
  const std::string detections = runs + "/kitti/detections";
  // Sequence 0001: the oxts file without its last line (frame 3).
  const std::string oxts = root + "/oxts/0001.txt";
  std::string text = test::ReadText(oxts);
  text.erase(text.find_last_of('\n', text.size() - 2) + 1);
  { std::ofstream(oxts, std::ios::trunc) << text; }
  const std::string out = runs + "/out";
  std::string err;
  EXPECT_EQ(RunSamp({"fit", "--model", scene.model, "--kitti-tracking", root, "--sequence", "all", "--detections",
                     detections, "--out", out, "-q"},
                    runs + "/log", &err),
            1)
      << err;
  EXPECT_NE(err.find(oxts + ":4: no GPS/IMU record for frame 3"), std::string::npos) << err;
  EXPECT_EQ(LastLine(err), "samp: error: 1 of 2 sequences failed: " + root + "/image_02/0001") << err;
  EXPECT_FALSE(ReadTrackingLabels(out + "/label_02/0000.txt").empty());
  EXPECT_FALSE(fs::exists(out + "/label_02/0001.txt"));
  // Sequence 0000's detections: the second line without its last two columns.
  const std::string detection_file = detections + "/0000.txt";
  std::istringstream lines(test::ReadText(detection_file));
  std::ostringstream cut;
  int n = 0;
  for (std::string line; std::getline(lines, line);) {
    if (++n == 2) line = line.substr(0, line.find_last_of(' ', line.find_last_of(' ') - 1));
    cut << line << "\n";
  }
  { std::ofstream(detection_file, std::ios::trunc) << cut.str(); }
  EXPECT_EQ(RunSamp({"fit", "--model", scene.model, "--kitti-tracking", root, "--sequence", "0", "--detections",
                     detections, "--out", runs + "/out2", "-q"},
                    runs + "/log", &err),
            1)
      << err;
  EXPECT_NE(err.find(detection_file + ":2: 16 columns, expected 17 or 18"), std::string::npos) << err;
  EXPECT_EQ(LastLine(err), "samp: error: every sequence failed") << err;
  EXPECT_FALSE(fs::exists(runs + "/out2/label_02/0000.txt"));
}

// SIGINT while the run writes: the second sequence's --tracks file is a FIFO
// that nobody writes, so the run blocks there after the first sequence's
// labels and meshes are in its temporary folder. The interrupted run leaves
// the earlier output exactly as it was and no temporary folder; the process
// ends by the signal.
TEST(FitCommand, InterruptedRunLeavesTheEarlierOutput) {
  const test::BoxCarScene& scene = TheScene();
  ASSERT_EQ(scene.sequences.size(), 2u);
  const std::string runs = TheScene().Folder("interrupted");
  const std::string out = runs + "/out";
  std::string err;
  ASSERT_EQ(RunSamp({"fit", "--model", scene.model, "--seq", scene.sequences[0], "--out", out, "-q"}, runs + "/log",
                    &err),
            0)
      << err;
  const std::string tracks_before = test::ReadText(out + "/tracks.json");
  const std::string labels_before = test::ReadText(out + "/label_02/" + scene.names[0] + ".txt");

  const std::string fifo = runs + "/blocked_tracks.txt";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string true_tracks = scene.sequences[0] + "/gt/label_02/" + scene.names[0] + ".txt";
  ASSERT_TRUE(fs::exists(true_tracks));
  const pid_t child = StartSamp({"fit", "--model", scene.model, "--seq", scene.sequences[0], "--seq",
                                 scene.sequences[1], "--tracks", true_tracks, "--tracks", fifo, "--out", out,
                                 "--threads", "2", "-q"},
                                runs + "/log_interrupted");
  ASSERT_GT(child, 0);
  // Wait until the first sequence's labels are in the temporary folder.
  const std::string prefix = ".tmp." + std::to_string(child) + ".";
  bool written = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(300);
  while (!written && std::chrono::steady_clock::now() < deadline) {
    for (const auto& entry : fs::directory_iterator(runs)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind(prefix, 0) == 0 &&
          fs::exists(entry.path() / "out/label_02" / (scene.names[0] + ".txt")) &&
          fs::exists(entry.path() / "out/meshes" / scene.names[0])) {
        written = true;
      }
    }
    int status = 0;
    if (!written && ::waitpid(child, &status, WNOHANG) == child) {
      FAIL() << "samp ended before it was interrupted: " << test::ReadText(runs + "/log_interrupted.err");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_TRUE(written) << "the first sequence's outputs never appeared";
  ASSERT_EQ(::kill(child, SIGINT), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << status;
  fs::remove(fifo);

  for (const auto& entry : fs::directory_iterator(runs)) {
    EXPECT_NE(entry.path().filename().string().rfind(".tmp.", 0), 0u) << "left behind: " << entry.path();
  }
  EXPECT_EQ(test::ReadText(out + "/tracks.json"), tracks_before);
  EXPECT_EQ(test::ReadText(out + "/label_02/" + scene.names[0] + ".txt"), labels_before);
  EXPECT_FALSE(fs::exists(out + "/label_02/" + scene.names[1] + ".txt"));
  EXPECT_FALSE(fs::exists(out + "/meshes/" + scene.names[0]));  // one sequence before: meshes/track_<id>.ply
}

}  // namespace
}  // namespace samp
