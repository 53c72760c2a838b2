// The fit's pictures and the reader of a fit output folder (libsamp/viz/fit_run.h,
// fit_pictures.h) on a hand-written run (fit_run_fixture.h).
#include "libsamp/viz/fit_pictures.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "libsamp/core/error.h"
#include "libsamp/viz/fit_run.h"
#include "tests/viz/fit_run_fixture.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

class FitRunTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const char* keep = std::getenv("SAMP_KEEP_TEST_OUTPUT");
    root_ = keep ? (fs::path(keep) / "fit_pictures").string()
                 : (fs::temp_directory_path() / ("samp_viz_fit_" + std::to_string(::getpid()))).string();
    fs::remove_all(root_);
    fixture_ = new testing::FitRunFixture(testing::WriteFitRunFixture(root_));
  }
  static void TearDownTestSuite() {
    delete fixture_;
    if (!std::getenv("SAMP_KEEP_TEST_OUTPUT")) fs::remove_all(root_);
  }
  static std::string root_;
  static testing::FitRunFixture* fixture_;
};
std::string FitRunTest::root_;
testing::FitRunFixture* FitRunTest::fixture_ = nullptr;

TEST(FrameIndexOfColor, InvertsTheWritersColourForEveryFrameCount) {
  for (int n = 1; n <= 256; ++n) {
    for (int k = 0; k < n; ++k) {
      const double a = n > 1 ? double(k) / (n - 1) : 0.0;
      ASSERT_EQ(FrameIndexOfColor(uint8_t(255 * a), 64, uint8_t(255 * (1 - a)), n), k) << "n " << n;
    }
  }
  EXPECT_EQ(FrameIndexOfColor(10, 63, 200, 21), -1);   // green is always 64
  EXPECT_EQ(FrameIndexOfColor(1, 64, 1, 21), -1);      // no frame has it
}

TEST(PoseFromYaw, MatchesTheFitsConvention) {
  // Heading (object +x) in the world is h = (cos θ, 0, −sin θ).
  const double yaw = 0.7;
  const Eigen::Isometry3d pose = PoseFromYaw(Eigen::Vector3d(1, 2, 3), yaw);
  EXPECT_TRUE((pose.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d(std::cos(yaw), 0, -std::sin(yaw))));
  EXPECT_TRUE(pose.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
}

TEST_F(FitRunTest, ReadsTracksPosesPointsDetectionsAndGroundTruth) {
  const FitRunView run = LoadFitRun(fixture_->output_dir);
  ASSERT_EQ(run.sequences.size(), 1u);
  const SequenceView& sequence = run.sequences[0];
  EXPECT_EQ(sequence.name, "0000");
  EXPECT_EQ(sequence.frames.size(), 21u);
  EXPECT_EQ(sequence.left_images.size(), 21u);
  EXPECT_EQ(sequence.camera.width, 1242);
  EXPECT_EQ(sequence.ground_plane_source, "fitted cars");
  EXPECT_NEAR(sequence.ground_plane_in_world[3], 1.65, 0.05);
  EXPECT_TRUE(sequence.world_from_camera.at(20).translation().isApprox(Eigen::Vector3d(0, 0, 6)));
  ASSERT_EQ(sequence.tracks.size(), fixture_->tracks.size());
  ASSERT_EQ(sequence.ground_truth.size(), fixture_->tracks.size());
  for (size_t t = 0; t < sequence.tracks.size(); ++t) {
    const TrackView& track = sequence.tracks[t];
    const testing::FixtureTrack& truth = fixture_->tracks[t];
    EXPECT_EQ(track.id, truth.id);
    EXPECT_EQ(track.mesh.triangles.size(), 12u);
    EXPECT_EQ(track.shape_code.size(), 3);
    EXPECT_EQ(track.code_in_sigmas.size(), 0);  // no model file: no sigmas
    ASSERT_EQ(track.frames.size(), 21u);
    for (size_t k = 0; k < track.frames.size(); ++k) {
      const TrackFrameView& f = track.frames[k];
      EXPECT_TRUE(f.world_from_object.isApprox(truth.fitted_world_from_object[k], 1e-6));
      // The points come back in the world, frame by frame (float precision).
      ASSERT_EQ(f.points_in_world.size(), truth.points_in_world[k].size()) << "frame " << k;
      // The PLY writer may swap two points: every 97th point has its twin among the true ones.
      double worst = 0.0;
      const std::vector<Eigen::Vector3f>& want = truth.points_in_world[k];
      for (size_t i = 0; i < f.points_in_world.size(); i += 97) {
        double best = 1e30;
        for (const Eigen::Vector3f& w : want) best = std::min(best, double((f.points_in_world[i] - w).norm()));
        worst = std::max(worst, best);
      }
      EXPECT_LT(worst, 1e-4) << "frame " << k;
      // The detection of the frame, nearest to the fitted pose.
      ASSERT_TRUE(f.has_detection) << "frame " << k;
      EXPECT_LT((f.world_from_detection.translation() - truth.true_world_from_object[k].translation()).norm(), 2.5);
      EXPECT_NEAR(f.detection_size.x(), 4.0, 1e-3);
      EXPECT_GT(f.detection_box_2d[2], f.detection_box_2d[0]);
    }
    // Matched to its true car; the true box is 0.1 m larger on every side.
    EXPECT_EQ(track.gt_track_id, truth.id);
    ASSERT_EQ(track.vertex_errors.size(), track.mesh.vertices.size());
    std::vector<float> errors = track.vertex_errors;
    std::sort(errors.begin(), errors.end());
    EXPECT_GT(errors.front(), 0.0);
    EXPECT_LT(errors.back(), 0.3);  // 0.1 m margin, fitted pose noise 3 cm and 0.01 rad
    EXPECT_NEAR(errors[errors.size() / 2], 0.1, 0.06);
  }
}

TEST_F(FitRunTest, MissingKeysAreNamed) {
  const fs::path broken = fs::path(root_) / "broken";
  fs::remove_all(broken);
  fs::create_directories(broken);
  std::ifstream in(fs::path(fixture_->output_dir) / "tracks.json");
  nlohmann::json j = nlohmann::json::parse(in);
  j["sequences"][0]["tracks"][0]["frames"][4].erase("yaw");
  std::ofstream(broken / "tracks.json") << j.dump();
  try {
    LoadFitRun(broken.string());
    FAIL() << "no error";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("tracks.json"), std::string::npos) << message;
    // The message of tracks.json's one reader (pipeline/fit_output.h ReadTracksFile).
    EXPECT_NE(message.find("sequences[0].tracks[0].frames[4]"), std::string::npos) << message;
    EXPECT_NE(message.find("'yaw'"), std::string::npos) << message;
  }
  EXPECT_THROW(LoadFitRun((fs::path(root_) / "nothing").string()), Error);
}

// Pixels of `image` close to `color` (within `tolerance` per channel).
int CountColor(const RgbImage& image, Rgb color, int tolerance) {
  int count = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const Rgb c = image.At(x, y);
      if (std::abs(c.r - color.r) <= tolerance && std::abs(c.g - color.g) <= tolerance &&
          std::abs(c.b - color.b) <= tolerance)
        ++count;
    }
  return count;
}

TEST_F(FitRunTest, OverlayShowsTheMeshAndTheDetectionBox) {
  const FitRunView run = LoadFitRun(fixture_->output_dir);
  FitPictureOptions options;
  const RgbImage overlay = RenderTrackOverlay(run.sequences[0], run.sequences[0].tracks[1], options);
  EXPECT_EQ(overlay.width, 26 + 4 * options.overlay_cell_width + 3 * 6);
  EXPECT_GT(CountColor(overlay, Rgb{20, 110, 220}, 4), 200);   // the mesh outline
  EXPECT_GT(CountColor(overlay, Rgb{230, 60, 40}, 4), 400);    // the detection boxes
  EXPECT_GT(PixelVariance(overlay), 100.0);
}

TEST_F(FitRunTest, WritesEveryPictureOfARun) {
  const FitRunView run = LoadFitRun(fixture_->output_dir);
  FitPictureOptions options;
  options.output_folder = (fs::path(root_) / "pictures").string();
  const FitPictureSummary summary = WriteFitPictures(run, options);
  // Per sequence one sheet, per track overlay, bird's-eye, shape and error surface.
  EXPECT_EQ(summary.files.size(), 1u + 4u * fixture_->tracks.size()) << summary.BriefReport();
  for (const std::string& file : summary.files) {
    const RgbImage image = ReadPng(file);
    EXPECT_GT(image.width, 200) << file;
    EXPECT_GT(PixelVariance(image), 50.0) << file;
  }
  EXPECT_TRUE(fs::exists(fs::path(options.output_folder) / "0000" / "birdseye.png"));
  EXPECT_TRUE(fs::exists(fs::path(options.output_folder) / "0000" / "track_4_birdseye.png"));
  EXPECT_TRUE(fs::exists(fs::path(options.output_folder) / "0000" / "track_4_error.png"));
}

TEST_F(FitRunTest, BirdsEyeAfterIsSharperThanBefore) {
  // The points aligned by the fitted poses (noise 3 cm) pile up on the car's
  // outline; aligned by the detections (noise 0.5 m) they smear: fewer pixels
  // of the "after" panel are touched.
  const FitRunView run = LoadFitRun(fixture_->output_dir);
  FitPictureOptions options;
  const RgbImage image = RenderTrackBirdsEye(run.sequences[0], run.sequences[0].tracks[2], options);
  const int size = options.birdseye_size, top = 50 + 40;  // title, caption
  auto touched = [&](int x0) {
    int n = 0;
    for (int y = top; y < top + size; ++y)
      for (int x = x0; x < x0 + size; ++x) {
        const Rgb c = image.At(x, y);
        const int hi = std::max({c.r, c.g, c.b}), lo = std::min({c.r, c.g, c.b});
        if (hi - lo > 12) ++n;  // coloured by frame (grid, box and mesh are grey)
      }
    return n;
  };
  const int before = touched(0), after = touched(size + 10);
  EXPECT_GT(before, int(1.3 * after)) << "before " << before << " after " << after;
}

TEST(FitPictureOptions, ChecksNameTheField) {
  FitPictureOptions options;
  options.overlay_frames = 0;
  try {
    options.Check();
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("overlay_frames"), std::string::npos);
  }
}

}  // namespace
}  // namespace samp
