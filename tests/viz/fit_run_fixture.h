// A `samp fit` output folder for the viz tests (tracks.json and config.json
// written by their one writer, pipeline/): a sequence
// directory (calib, poses, image_2, detections, gt/) and OUT/ (tracks.json,
// config.json, meshes/ with box cars and their aligned points), as
// docs/fitting.md and docs/synthetic.md describe them. Seeded; the true values
// are kept for the checks.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace samp::testing {

struct FixtureOptions {
  int num_tracks = 5;
  int num_frames = 21;
  int points_per_frame = 3000;
  int image_width = 1242, image_height = 375;
  bool ground_truth = true;
  unsigned seed = 7;
};

struct FixtureTrack {
  int id = 0;
  std::vector<Eigen::Isometry3d> true_world_from_object, fitted_world_from_object;
  std::vector<std::vector<Eigen::Vector3f>> points_in_world;  // per frame
};

struct FitRunFixture {
  std::string sequence_dir, output_dir, sequence_name = "0000";
  std::vector<FixtureTrack> tracks;
  double gt_margin = 0.1;  // the true boxes are this much larger on every side, m
};

// Writes the sequence under `root`/seq and the fit under `root`/out.
FitRunFixture WriteFitRunFixture(const std::string& root, const FixtureOptions& options = {});

}  // namespace samp::testing
