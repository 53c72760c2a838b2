// RunFit on a small synthetic sequence (the clean preset of docs/synthetic.md,
// the box-car model of the eval tests): the output folder holds one run only,
// a run that throws leaves it as it was, folders that are not samp's are not
// replaced, same-named sequences are refused, and a solve that Ceres cannot
// use is a failed track.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <limits>
#include <fstream>
#include <set>
#include <sstream>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/core/json_fields.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/synth/synth.h"
#include "libsamp/pipeline/fit_config.h"
#include "libsamp/pipeline/fit_output.h"
#include "libsamp/pipeline/run_fit.h"
#include "tests/synth/test_scene.h"
#include "tests/testing/expect_error.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

// One 4-frame sequence, synthesised once per test binary (seeded).
const test::BoxCarScene& TheScene() {
  static const test::BoxCarScene scene("run_fit", 5, 1, 4);
  return scene;
}

RunFitOptions Options(const std::string& model, const std::vector<std::string>& sequences,
                      const std::string& out) {
  RunFitOptions o;
  o.model_path = model;
  o.sequences = sequences;
  o.output_dir = out;
  o.fit.max_iterations = 30;
  return o;
}

// Options whose every solve Ceres rejects: the smallest positive
// sigma_ground (FitOptions::Check accepts it) makes the ground prior's scale
// sqrt(w) / sigma_ground infinite, so its residual and Jacobian are inf or
// NaN at the first evaluation and Ceres ends with FAILURE ("Residual and
// Jacobian evaluation failed"), IsSolutionUsable() false.
RunFitOptions UnusableOptions(const std::vector<std::string>& sequences, const std::string& out) {
  RunFitOptions o = Options(TheScene().model, sequences, out);
  o.fit.sigma_ground = std::numeric_limits<double>::denorm_min();
  return o;
}

// Every path under `folder`, relative, sorted.
std::set<std::string> Listing(const std::string& folder) {
  std::set<std::string> paths;
  for (const auto& entry : fs::recursive_directory_iterator(folder))
    paths.insert(entry.path().lexically_relative(folder).string());
  return paths;
}

// The names in `folder` that start with ".tmp." (temporaries of samp).
std::vector<std::string> Temporaries(const std::string& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(".tmp.", 0) == 0) names.push_back(name);
  }
  return names;
}

using test::ErrorOf;

// A run that fits tracks writes labels and meshes; a later successful run
// into the same folder replaces it as a whole: no label line, mesh, picture
// or page of the earlier run survives. A failed run (no track fitted, every
// sequence failed, one sequence of a batch failed) never replaces it: the
// earlier output stays byte-identical (samp fit exits 1).
TEST(RunFit, ReplacesTheOutputOfAnEarlierRun) {
  const test::BoxCarScene& scene = TheScene();
  const std::string runs = TheScene().Folder("replace");
  const std::string out = runs + "/out";
  const std::string labels = out + "/label_02/" + scene.names[0] + ".txt";

  const RunFitSummary first = RunFit(Options(scene.model, {scene.sequences[0]}, out));
  ASSERT_GT(first.num_tracks_fitted, 0) << first.BriefReport();
  EXPECT_EQ(first.failure, "");
  EXPECT_FALSE(first.replaced_previous_output);
  ASSERT_FALSE(ReadTrackingLabels(labels).empty());
  ASSERT_TRUE(fs::is_directory(out + "/meshes"));
  EXPECT_TRUE(fs::is_regular_file(out + "/" + kOutputFolderMarker));
  // What `samp view` and --pictures add to a fit folder (recorded in its marker).
  WriteTextFileAtomically(out + "/index.html", "<html></html>");
  WriteTextFileAtomically(out + "/pictures/" + scene.names[0] + "/birdseye.png", "png");
  RecordInOutputFolder(out, {out + "/index.html", out + "/pictures/" + scene.names[0] + "/birdseye.png"});
  const std::set<std::string> earlier = Listing(out);
  const std::string earlier_labels = test::ReadText(labels);

  // Failed runs keep the earlier output. Zero tracks fitted (every solve unusable):
  const RunFitSummary second = RunFit(UnusableOptions({scene.sequences[0]}, out));
  EXPECT_EQ(second.num_tracks_fitted, 0);
  EXPECT_NE(second.failure, "");
  EXPECT_FALSE(second.replaced_previous_output);
  EXPECT_TRUE(second.kept_previous_output);
  EXPECT_EQ(Listing(out), earlier);
  EXPECT_EQ(test::ReadText(labels), earlier_labels);
  // Every sequence failed (a folder that is no sequence):
  const RunFitSummary third = RunFit(Options(scene.model, {runs + "/no_such_sequence"}, out));
  EXPECT_EQ(third.num_sequences_failed, 1);
  EXPECT_EQ(third.failure, "every sequence failed");
  EXPECT_TRUE(third.kept_previous_output);
  EXPECT_EQ(Listing(out), earlier);
  // One sequence of a batch failed:
  const RunFitSummary batch = RunFit(Options(scene.model, {scene.sequences[0], runs + "/no_such_sequence"}, out));
  EXPECT_EQ(batch.num_sequences_failed, 1);
  EXPECT_NE(batch.failure.find("1 of 2 sequences failed: " + runs + "/no_such_sequence"), std::string::npos)
      << batch.failure;
  EXPECT_TRUE(batch.kept_previous_output);
  EXPECT_EQ(Listing(out), earlier);
  EXPECT_EQ(test::ReadText(labels), earlier_labels);

  // A successful run replaces everything (here without meshes).
  RunFitOptions no_meshes = Options(scene.model, {scene.sequences[0]}, out);
  no_meshes.write_meshes = false;
  const RunFitSummary fourth = RunFit(no_meshes);
  EXPECT_EQ(fourth.failure, "");
  EXPECT_TRUE(fourth.replaced_previous_output);
  // detector_model.json: the self-calibrated detector model (on by default).
  EXPECT_EQ(Listing(out), (std::set<std::string>{kOutputFolderMarker, "config.json", "detector_model.json",
                                                 "label_02", "label_02/" + scene.names[0] + ".txt",
                                                 "tracks.json"}));

  // A failed run into a new folder is written (its tracks.json says why).
  const std::string fresh = runs + "/fresh";
  const RunFitSummary failed_fresh = RunFit(Options(scene.model, {runs + "/no_such_sequence"}, fresh));
  EXPECT_EQ(failed_fresh.failure, "every sequence failed");
  EXPECT_FALSE(failed_fresh.kept_previous_output);
  EXPECT_EQ(Listing(fresh),
            (std::set<std::string>{kOutputFolderMarker, "config.json", "detector_model.json", "tracks.json"}));
  EXPECT_FALSE(ReadTracksFile(fresh + "/tracks.json").sequences.at(0).ok);
  EXPECT_TRUE(Temporaries(runs).empty());
}

// A run that throws (a model that does not load, an error in what is written
// last) leaves the earlier output exactly as it was and no temporary folder.
TEST(RunFit, RunThatThrowsLeavesTheOutputAsItWas) {
  const test::BoxCarScene& scene = TheScene();
  const std::string runs = TheScene().Folder("throws");
  const std::string out = runs + "/out";
  RunFitOptions options = Options(scene.model, {scene.sequences[0]}, out);
  options.write_meshes = false;
  ASSERT_GT(RunFit(options).num_tracks_fitted, 0);
  const std::set<std::string> listing = Listing(out);
  const std::string tracks = test::ReadText(out + "/tracks.json");

  RunFitOptions no_model = options;
  no_model.model_path = runs + "/missing.vdb";
  EXPECT_THROW(RunFit(no_model), Error);

  RunFitOptions failing = options;
  failing.write_meshes = true;
  bool called = false;
  failing.before_commit = [&](const std::string& folder) {
    called = true;
    // Everything of the new run is there, under the output's name.
    EXPECT_EQ(fs::path(folder).filename(), "out");
    EXPECT_TRUE(fs::is_directory(folder + "/meshes"));
    EXPECT_TRUE(fs::exists(folder + "/config.json"));
    SAMP_THROW() << "pictures failed";
  };
  EXPECT_EQ(ErrorOf([&] { RunFit(failing); }), "pictures failed");
  EXPECT_TRUE(called);

  EXPECT_EQ(Listing(out), listing);
  EXPECT_EQ(test::ReadText(out + "/tracks.json"), tracks);
  EXPECT_TRUE(Temporaries(runs).empty());
}

// Only new, empty or samp-made folders (marker file listing every file) are
// replaced; the others are refused
// before anything is read, and stay as they were.
TEST(RunFit, RefusesOutputFoldersItMustNotReplace) {
  const test::BoxCarScene& scene = TheScene();
  const std::string runs = TheScene().Folder("refuse");

  const std::string file = runs + "/a_file";
  WriteTextFileAtomically(file, "keep");
  EXPECT_NE(ErrorOf([&] { RunFit(Options(scene.model, {scene.sequences[0]}, file)); }).find("is not a folder"),
            std::string::npos);
  EXPECT_EQ(test::ReadText(file), "keep");

  const std::string mine = runs + "/my_folder";
  WriteTextFileAtomically(mine + "/notes.txt", "keep");
  const std::string message = ErrorOf([&] { RunFit(Options(scene.model, {scene.sequences[0]}, mine)); });
  EXPECT_NE(message.find(mine), std::string::npos) << message;
  EXPECT_NE(message.find("was not made by samp"), std::string::npos) << message;
  EXPECT_EQ(Listing(mine), (std::set<std::string>{"notes.txt"}));

  // A user's folder that merely looks like a fit output (the case of issue 32:
  // tracks.json and config.json beside a thesis) is not samp's.
  const std::string thesis = runs + "/thesis";
  WriteTextFileAtomically(thesis + "/tracks.json", "{}");
  WriteTextFileAtomically(thesis + "/config.json", "{}");
  WriteTextFileAtomically(thesis + "/thesis.tex", "t");
  EXPECT_NE(ErrorOf([&] { RunFit(Options(scene.model, {scene.sequences[0]}, thesis)); }).find("was not made by samp"),
            std::string::npos);
  EXPECT_EQ(test::ReadText(thesis + "/thesis.tex"), "t");

  // An earlier samp run with a file added by the user: refused, naming it.
  const std::string earlier = runs + "/earlier";
  RunFitOptions link = Options(scene.model, {scene.sequences[0]}, earlier);
  link.link_only = true;
  ASSERT_EQ(RunFit(link).failure, "");
  WriteTextFileAtomically(earlier + "/label_02/my_notes.txt", "mine");
  const std::string foreign = ErrorOf([&] { RunFit(link); });
  EXPECT_NE(foreign.find("holds 1 file(s) samp did not write: label_02/my_notes.txt"), std::string::npos) << foreign;
  EXPECT_EQ(test::ReadText(earlier + "/label_02/my_notes.txt"), "mine");
  // A forged marker does not list the user's file either.
  WriteTextFileAtomically(thesis + "/" + kOutputFolderMarker, "samp output folder\nrun_id 0\nfile tracks.json\n");
  EXPECT_NE(ErrorOf([&] { RunFit(Options(scene.model, {scene.sequences[0]}, thesis)); })
                .find("samp did not write: config.json, thesis.tex"),
            std::string::npos);

  // An input reached through a hard link inside an earlier run's folder.
  fs::remove(earlier + "/label_02/my_notes.txt");
  const std::string model_link = earlier + "/model_copy.vdb";
  fs::create_hard_link(scene.model, model_link);
  RecordInOutputFolder(earlier, {model_link});
  const std::string linked = ErrorOf([&] { RunFit(Options(scene.model, {scene.sequences[0]}, earlier)); });
  EXPECT_NE(linked.find("holds the input model"), std::string::npos) << linked;
  EXPECT_TRUE(fs::exists(scene.model));

  // The folder that holds the sequence (or the model, or is the sequence).
  const std::string parent = fs::path(scene.sequences[0]).parent_path().string();
  const std::string holds = ErrorOf([&] { RunFit(Options(scene.model, {scene.sequences[0]}, parent)); });
  EXPECT_NE(holds.find("holds the input sequence " + scene.sequences[0]), std::string::npos) << holds;
  EXPECT_NE(ErrorOf([&] { RunFit(Options(scene.model, {scene.sequences[0]}, scene.sequences[0] + "/")); })
                .find("holds the input sequence"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { RunFit(Options(scene.model, {scene.sequences[0]}, scene.root)); }).find("holds the input"),
            std::string::npos);

  // The current folder (or one holding it).
  const fs::path cwd = fs::current_path();
  fs::current_path(runs);
  const std::string here = ErrorOf([&] { RunFit(Options(scene.model, {scene.sequences[0]}, ".")); });
  fs::current_path(cwd);
  EXPECT_NE(here.find("is the current folder"), std::string::npos) << here;

  // An empty folder is fine.
  const std::string empty = runs + "/empty";
  fs::create_directories(empty);
  RunFitOptions options = Options(scene.model, {scene.sequences[0]}, empty);
  options.link_only = true;
  EXPECT_EQ(RunFit(options).failure, "");
  EXPECT_TRUE(fs::exists(empty + "/tracks.json"));
  EXPECT_TRUE(Temporaries(runs).empty());
}

// Two sequences with one name would write the same label_02/<seq>.txt and
// meshes/<seq>/: an error naming both paths before anything is fitted.
TEST(RunFit, SameNamedSequencesAreAnError) {
  const test::BoxCarScene& scene = TheScene();
  const std::string runs = TheScene().Folder("same_name");
  const std::string a = runs + "/a/" + scene.names[0], b = runs + "/b/" + scene.names[0];
  fs::create_directories(runs + "/a");
  fs::create_directories(runs + "/b");
  fs::copy(scene.sequences[0], a, fs::copy_options::recursive);
  fs::copy(scene.sequences[0], b, fs::copy_options::recursive);
  const std::string out = runs + "/out";
  const std::string message = ErrorOf([&] { RunFit(Options(scene.model, {a, b}, out)); });
  EXPECT_NE(message.find(a + " and " + b), std::string::npos) << message;
  EXPECT_NE(message.find("'" + scene.names[0] + "'"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(out));
  // The same folder twice, once with a trailing slash; and a folder that is
  // no sequence (named by its folder) beside a sequence of that name.
  EXPECT_NE(ErrorOf([&] { RunFit(Options(scene.model, {a, a + "/"}, out)); }).find("the same name"),
            std::string::npos);
  const std::string not_a_sequence = runs + "/c/" + scene.names[0];
  fs::create_directories(not_a_sequence);
  EXPECT_NE(ErrorOf([&] { RunFit(Options(scene.model, {a, not_a_sequence}, out)); }).find("the same name"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(SequenceOutputName(a + "/"), scene.names[0]);
}

// A solve that Ceres marks not usable is a failed track: listed with its
// reason, no label line, mesh or record; a run where every track failed has
// a failure (samp fit exits 1) and the hook of a successful run is not called.
TEST(RunFit, UnusableSolveIsAFailedTrack) {
  const test::BoxCarScene& scene = TheScene();
  const std::string out = TheScene().Folder("unusable") + "/out";
  RunFitOptions options = UnusableOptions({scene.sequences[0]}, out);
  bool called = false;
  options.before_commit = [&](const std::string&) { called = true; };
  const RunFitSummary summary = RunFit(options);
  ASSERT_EQ(summary.sequences.size(), 1u);
  const SequenceFitResult& sequence = summary.sequences[0];
  ASSERT_TRUE(sequence.ok) << sequence.error;
  ASSERT_GT(sequence.num_tracks, 0);
  EXPECT_EQ(sequence.num_fitted, 0);
  ASSERT_EQ(int(sequence.track_failures.size()), sequence.num_tracks);
  for (const std::string& failure : sequence.track_failures) {
    EXPECT_NE(failure.find("solve 1 of"), std::string::npos) << failure;
    EXPECT_NE(failure.find("is not usable: FAILURE"), std::string::npos) << failure;
  }
  EXPECT_EQ(summary.num_tracks_fitted, 0);
  EXPECT_EQ(summary.num_tracks_failed, sequence.num_tracks);
  EXPECT_NE(summary.failure.find("no track was fitted although the input had"), std::string::npos)
      << summary.failure;
  EXPECT_NE(summary.failure.find("every track failed (" + std::to_string(sequence.num_tracks) + ")"),
            std::string::npos)
      << summary.failure;
  EXPECT_FALSE(called);
  EXPECT_TRUE(ReadTrackingLabels(out + "/label_02/" + scene.names[0] + ".txt").empty());
  EXPECT_FALSE(fs::exists(out + "/meshes"));
  const TracksFile tracks = ReadTracksFile(out + "/tracks.json");
  EXPECT_TRUE(tracks.sequences.at(0).tracks.empty());
  EXPECT_EQ(tracks.sequences.at(0).failed_tracks, sequence.track_failures);

  // The same input with the default sigma_ground: every track is fitted (so
  // the failure above is that option's, nothing else).
  const RunFitSummary good = RunFit(Options(scene.model, {scene.sequences[0]}, out));
  EXPECT_EQ(good.num_tracks_fitted, sequence.num_tracks) << good.BriefReport();
  EXPECT_EQ(good.failure, "");
}

// The temporary output folder of a run killed with -9 is removed by the next
// run beside it; one of a running process is kept.
TEST(RunFit, RemovesTheTemporaryFolderOfAKilledRun) {
  const test::BoxCarScene& scene = TheScene();
  const std::string runs = TheScene().Folder("killed");
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) ::_exit(0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);  // `child` no longer runs
  const std::string orphan = runs + "/.tmp." + std::to_string(child) + ".0.out";
  WriteTextFileAtomically(orphan + "/out/label_02/" + scene.names[0] + ".txt", "");
  WriteTextFileAtomically(orphan + "/out/meshes/track_1.ply", "ply");
  const std::string alive = runs + "/.tmp." + std::to_string(::getppid()) + ".0.out";
  fs::create_directories(alive + "/out");
  RunFitOptions options = Options(scene.model, {scene.sequences[0]}, runs + "/out");
  options.link_only = true;
  RunFit(options);
  EXPECT_FALSE(fs::exists(orphan));
  EXPECT_TRUE(fs::exists(alive));
  EXPECT_TRUE(fs::exists(runs + "/out/tracks.json"));
}

}  // namespace
}  // namespace samp

namespace samp {
namespace {

// The "detector_model" object of OUT/tracks.json.
nlohmann::json TracksDetectorModel(const std::string& out) {
  return ReadJsonFile(out + "/tracks.json").at("detector_model");
}

// Self-calibration on the small scene: too few detections for an estimate,
// so every term keeps the given sigmas with a note; the model and its sample
// counts go to the summary, OUT/detector_model.json and tracks.json (the same
// object), the option to config.json. Off (--no-self-calibrate): no
// detector_model.json, tracks.json says no model was used and why.
TEST(RunFitCalibration, SelfCalibrationWritesTheModel) {
  const test::BoxCarScene& scene = TheScene();
  const std::string runs = scene.Folder("calibrate");
  RunFitOptions o = Options(scene.model, {scene.sequences[0]}, runs + "/on");
  o.self_calibrate = true;
  const RunFitSummary on = RunFit(o);
  ASSERT_GT(on.num_tracks_fitted, 0) << on.BriefReport();
  EXPECT_TRUE(on.detector_model_used);
  EXPECT_NE(on.BriefReport().find("detector self-calibration"), std::string::npos) << on.BriefReport();
  EXPECT_EQ(on.detector_model.source, "defaults");
  EXPECT_FALSE(on.detector_model.notes.empty());
  const DetectorNoiseModel written = ReadDetectorNoiseModel(runs + "/on/detector_model.json");
  EXPECT_EQ(written.ToJson(), on.detector_model.ToJson());
  EXPECT_EQ(written.size_sigma[0], o.sequence.tracker.size_sigma);
  const nlohmann::json record = TracksDetectorModel(runs + "/on");
  EXPECT_EQ(record.at("origin"), "self-calibration");
  EXPECT_EQ(record.at("model"), ReadJsonFile(runs + "/on/detector_model.json"));
  EXPECT_EQ(record.at("model").at("source"), "defaults");
  EXPECT_EQ(record.at("model").at("samples").at("frames"), on.detector_model.num_frames);
  EXPECT_GT(on.detector_model.num_frames, 0);
  EXPECT_EQ(record.at("model").at("notes").size(), on.detector_model.notes.size());
  EXPECT_EQ(ReadTracksFile(runs + "/on/tracks.json").detector_model.model.ToJson(), on.detector_model.ToJson());
  std::ifstream config(runs + "/on/config.json");
  const std::string text((std::istreambuf_iterator<char>(config)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"self_calibrate\": true"), std::string::npos);
  // config.json records the same model, with the options it came from.
  EXPECT_EQ(ReadJsonFile(runs + "/on/config.json").at("detector_model_used"), record);
  EXPECT_EQ(ReadFitConfig(runs + "/on/config.json").detector_model.model.ToJson(), on.detector_model.ToJson());

  RunFitOptions o_off = Options(scene.model, {scene.sequences[0]}, runs + "/off");
  o_off.self_calibrate = false;  // --no-self-calibrate
  const RunFitSummary off = RunFit(o_off);
  EXPECT_FALSE(off.detector_model_used);
  EXPECT_FALSE(fs::exists(runs + "/off/detector_model.json"));
  const nlohmann::json record_off = TracksDetectorModel(runs + "/off");
  EXPECT_EQ(record_off.at("origin"), "none");
  EXPECT_NE(record_off.at("reason").get<std::string>().find("self-calibration off"), std::string::npos);
  EXPECT_FALSE(record_off.contains("model"));
  EXPECT_EQ(ReadJsonFile(runs + "/off/config.json").at("detector_model_used"), record_off);
  std::ifstream config_off(runs + "/off/config.json");
  const std::string text_off((std::istreambuf_iterator<char>(config_off)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text_off.find("self_calibrate"), std::string::npos);
  EXPECT_EQ(text_off.find("robust_cues"), std::string::npos);
}

// A detector model file replaces the tracker's sigmas; a bad one is a clear
// error before anything is written; a given file is used instead of
// self-calibration (which is on by default).
TEST(RunFitCalibration, DetectorModelFile) {
  const test::BoxCarScene& scene = TheScene();
  const std::string runs = scene.Folder("detector_model");
  fs::create_directories(runs);
  DetectorNoiseModel model;
  model.source = "ground truth";
  model.size_sigma[0] = model.size_sigma[1] = model.size_sigma[2] = 0.5;
  WriteDetectorNoiseModel(runs + "/model.json", model);
  RunFitOptions o = Options(scene.model, {scene.sequences[0]}, runs + "/out");
  o.detector_model_path = runs + "/model.json";
  const RunFitSummary summary = RunFit(o);
  ASSERT_GT(summary.num_tracks_fitted, 0) << summary.BriefReport();
  EXPECT_TRUE(summary.detector_model_used);
  EXPECT_NE(summary.calibration_report.find("read from"), std::string::npos);
  EXPECT_EQ(ReadDetectorNoiseModel(runs + "/out/detector_model.json").size_sigma[1], 0.5);
  const nlohmann::json record = TracksDetectorModel(runs + "/out");
  EXPECT_EQ(record.at("origin"), "file");
  EXPECT_EQ(record.at("file"), runs + "/model.json");
  EXPECT_EQ(record.at("model"), ReadJsonFile(runs + "/out/detector_model.json"));
  EXPECT_EQ(record.at("model").at("source"), "ground truth");
  EXPECT_EQ(ReadJsonFile(runs + "/out/config.json").at("detector_model_used"), record);

  WriteTextFileAtomically(runs + "/bad.json", "{\"format\": \"samp-detector-model\", \"version\": 9}");
  o.detector_model_path = runs + "/bad.json";
  o.output_dir = runs + "/bad_out";
  test::ExpectError([&] { RunFit(o); }, {"bad.json", "version 9"});
  EXPECT_FALSE(fs::exists(runs + "/bad_out"));
  o.self_calibrate = true;
  o.detector_model_path = runs + "/model.json";
  o.output_dir = runs + "/file_wins";
  const RunFitSummary file_wins = RunFit(o);
  EXPECT_NE(file_wins.calibration_report.find("read from"), std::string::npos) << file_wins.calibration_report;
  EXPECT_EQ(TracksDetectorModel(runs + "/file_wins").at("origin"), "file");
}

// The detector model's plot goes through RunFitOptions::draw_detector_model
// (the pipeline does not draw; `samp fit` sets viz's plot): called once with
// OUT/detector_model.png in the temporary folder and the run's model, so the
// file is part of the output; not called with detector_plot off (config.json
// then says so, and only then) or without a model; a hook that throws leaves
// the output as it was. Linking only: self-calibration runs all the same.
TEST(RunFitCalibration, DetectorModelPlotHook) {
  const test::BoxCarScene& scene = TheScene();
  const std::string runs = scene.Folder("detector_plot");
  const std::string out = runs + "/out";
  RunFitOptions o = Options("", {scene.sequences[0]}, out);
  o.link_only = true;
  std::vector<std::string> paths;
  std::string drawn_model;
  o.draw_detector_model = [&](const std::string& path, const DetectorNoiseModel& model) {
    paths.push_back(path);
    drawn_model = model.ToJson();
    WriteTextFileAtomically(path, "plot of " + model.source + "\n");
  };
  const RunFitSummary first = RunFit(o);
  ASSERT_TRUE(first.detector_model_used) << first.BriefReport();
  ASSERT_EQ(paths.size(), 1u);
  EXPECT_EQ(fs::path(paths[0]).filename(), "detector_model.png");
  EXPECT_NE(fs::path(paths[0]).parent_path(), fs::path(out));  // the temporary folder
  EXPECT_EQ(drawn_model, first.detector_model.ToJson());
  EXPECT_EQ(Listing(out), (std::set<std::string>{kOutputFolderMarker, "config.json", "detector_model.json",
                                                 "detector_model.png", "label_02",
                                                 "label_02/" + scene.names[0] + ".txt", "tracks.json"}));
  EXPECT_FALSE(ReadJsonFile(out + "/config.json").contains("detector_plot"));
  EXPECT_TRUE(ReadFitConfig(out + "/config.json").options.detector_plot);

  // Off: no call, no file; config.json records the option. The earlier run
  // (its plot listed in its marker) is replaced.
  o.detector_plot = false;
  const RunFitSummary off = RunFit(o);
  EXPECT_TRUE(off.replaced_previous_output);
  EXPECT_EQ(paths.size(), 1u);
  EXPECT_FALSE(fs::exists(out + "/detector_model.png"));
  EXPECT_EQ(ReadJsonFile(out + "/config.json").at("detector_plot"), false);
  EXPECT_FALSE(ReadFitConfig(out + "/config.json").options.detector_plot);

  // No detector model (self-calibration off, no file): nothing to draw.
  o.detector_plot = true;
  o.self_calibrate = false;
  RunFit(o);
  EXPECT_EQ(paths.size(), 1u);
  EXPECT_FALSE(fs::exists(out + "/detector_model.png"));
  // No hook: no plot.
  o.self_calibrate = true;
  o.draw_detector_model = nullptr;
  RunFit(o);
  EXPECT_TRUE(fs::exists(out + "/detector_model.json"));
  EXPECT_FALSE(fs::exists(out + "/detector_model.png"));

  // A hook that throws: the run throws, the output stays as it was.
  const std::set<std::string> before = Listing(out);
  o.draw_detector_model = [](const std::string& path, const DetectorNoiseModel&) {
    SAMP_THROW() << "cannot draw " << path;
  };
  test::ExpectError([&] { RunFit(o); }, {"cannot draw ", "detector_model.png"});
  EXPECT_EQ(Listing(out), before);
  EXPECT_TRUE(Temporaries(runs).empty());
}

}  // namespace
}  // namespace samp
