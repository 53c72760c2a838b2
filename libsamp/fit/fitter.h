// Joint shape and trajectory fit of one tracked car (SAMP, Sections 3.2-3.4;
// docs/fitting.md): one shape code z shared by all frames, per frame a pose
// (t, theta) and velocities (v, omega), minimising with Ceres
// Levenberg-Marquardt
//   E = (1/T) sum_t [E_data,t + E_motion,t + E_ground,t] + E_shape
// with hard EM over the point association. Also the single-frame mode (the
// authors' GCPR 2016 method): a shape per frame and no motion term.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "libsamp/core/mesh.h"
#include "libsamp/fit/fit_options.h"
#include "libsamp/fit/initialization.h"
#include "libsamp/model/shape_lookup.h"
#include "libsamp/data/track.h"

namespace samp {

// One Ceres solve.
struct SolveReport {
  double initial_cost = 0.0;  // Ceres cost (1/2 E) before and after
  double final_cost = 0.0;
  int num_iterations = 0;     // LM iterations (successful + unsuccessful)
  double seconds = 0.0;       // wall time of ceres::Solve (set-up, initial evaluation, steps)
  double median_step_seconds = 0.0;  // median Ceres iteration time over the LM steps (0 if none)
  bool usable = false;        // ceres::Solver::Summary::IsSolutionUsable()
  std::string termination;    // Ceres' termination type and message
  int num_points = 0;         // data points in the problem
};

struct FitSummary {
  std::vector<SolveReport> solves;  // initial solve, then one per EM iteration
  // Frames whose EM association kept fewer than min_points_per_frame points,
  // one line each with the reason ("frame 7: 3 of 812 candidates kept: ...").
  std::vector<std::string> association_notes;
  double initial_cost = 0.0;        // first solve, before
  double final_cost = 0.0;          // last solve, after
  int num_iterations = 0;           // summed over solves
  double seconds = 0.0;             // whole fit including association
  bool usable = false;              // every solve usable
  int num_frames_reset = 0;         // frames reset to their initial pose (FitOptions::max_position_change)
  // kDisparity: candidate points dropped because they are not in front of the
  // camera (no disparity), summed over the frames (each frame's candidates once).
  int num_points_behind_camera = 0;
  std::string BriefReport() const;
  // Why the fit cannot be reported as fitted: the first solve Ceres marks not
  // usable (IsSolutionUsable() false: its number and termination), or no solve
  // at all. Empty when every solve is usable.
  std::string UnusableReason() const;
};

struct FrameFit {
  int frame = 0;
  double time = 0.0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // object origin in the world
  double yaw = 0.0;                                     // about world y, (-pi, pi]
  double speed = 0.0;                                   // m/s (single-frame: finite differences)
  double yaw_rate = 0.0;                                // rad/s
  // Model predicting this frame from the previous one in the last solve
  // (frame 0 and single-frame mode: "none").
  std::string motion_model = "none";
  int num_points = 0;                                   // associated in the last solve
  double effective_points = 0.0;                        // N_eff of the last solve (kEffective), else num_points
  double data_cost = 0.0;                               // (1/N) sum rho(s_i) at the solution, over the last solve's points (the capped subsample)
  std::vector<Eigen::Vector3d> points_in_world;         // when options.keep_points
  Eigen::VectorXd shape_code;                           // single-frame mode only
  Eigen::Isometry3d WorldFromObject() const;
};

struct TrackFit {
  int track_id = 0;
  std::string sequence;
  std::string type = "Car";
  bool single_frame = false;
  Eigen::VectorXd shape_code;  // joint mode (single-frame: the mean of the frames' codes)
  std::vector<FrameFit> frames;
  FitSummary summary;
};

// Fits tracks against one shape model. Holds a ShapeLookup (the model
// re-laid out); Fit() is const and may be called concurrently.
class TrackFitter {
 public:
  TrackFitter(const ShapeModel& model, const FitOptions& options);

  // Throws samp::Error naming the track on bad input (no frames,
  // non-increasing times, no frame with enough points, non-finite values).
  // A one-frame track is fitted in joint mode too (no motion term: the
  // single-frame problem). Non-convergence is reported in the summary, not thrown.
  TrackFit Fit(const Track& track) const;

  const ShapeLookup& lookup() const { return lookup_; }
  const FitOptions& options() const { return options_; }

 private:
  ShapeLookup lookup_;
  FitOptions options_;
  ceres::LinearSolverType linear_solver_;  // options_.linear_solver, checked once
};

}  // namespace samp
