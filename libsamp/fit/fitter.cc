#include "libsamp/fit/fitter.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/core/pose.h"
#include "libsamp/core/util.h"
#include "libsamp/fit/association.h"
#include "libsamp/fit/track_problem.h"

namespace samp {

namespace {

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// "track 7 of sequence 0003": how errors and log lines name a track.
std::string TrackName(const Track& track) {
  return "track " + std::to_string(track.id) + (track.sequence.empty() ? "" : " of sequence " + track.sequence);
}

void CheckTrack(const Track& track, const std::string& name) {
  SAMP_CHECK(!track.frames.empty()) << name << " has no frames";
  for (size_t k = 0; k < track.frames.size(); ++k) {
    const TrackFrame& f = track.frames[k];
    SAMP_CHECK(f.candidate_points_in_world.size() == f.candidate_sigmas.size())
        << name << " frame " << f.frame << ": " << f.candidate_points_in_world.size()
        << " points but " << f.candidate_sigmas.size() << " sigmas";
    SAMP_CHECK(std::isfinite(f.time)) << name << " frame " << f.frame << ": time is not finite";
    SAMP_CHECK(f.detection.position.allFinite() && std::isfinite(f.detection.rotation_y))
        << name << " frame " << f.frame << ": detection is not finite";
    SAMP_CHECK(f.world_from_camera.matrix().allFinite())
        << name << " frame " << f.frame << ": ego pose is not finite";
    SAMP_CHECK(f.ground_plane_in_world.allFinite() &&
               std::abs(f.ground_plane_in_world.head<3>().norm() - 1.0) < 1e-3)
        << name << " frame " << f.frame << ": ground plane must be finite with a unit normal";
    for (size_t i = 0; i < f.candidate_points_in_world.size(); ++i) {
      SAMP_CHECK(f.candidate_points_in_world[i].allFinite() && f.candidate_sigmas[i] > 0.0 &&
                 std::isfinite(f.candidate_sigmas[i]))
          << name << " frame " << f.frame << ": point " << i << " or its sigma is invalid";
    }
    if (k > 0) {
      SAMP_CHECK(f.time > track.frames[k - 1].time)
          << name << ": frame times must increase (frame " << f.frame << ")";
    }
  }
}

// Ends a solve after this many consecutive rejected LM steps: the cost sits
// at a kink of the residuals (with the ray-distance data term, rays that
// switch between meeting and missing the surface make the cost jump by
// ~1e-3 for any step), where shrinking the trust region gains nothing.
class StopAfterRejectedSteps : public ceres::IterationCallback {
 public:
  explicit StopAfterRejectedSteps(int max_rejected) : max_rejected_(max_rejected) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    rejected_ = summary.iteration > 0 && !summary.step_is_successful ? rejected_ + 1 : 0;
    return rejected_ >= max_rejected_ ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }

 private:
  int max_rejected_;
  int rejected_ = 0;
};

// One Levenberg-Marquardt solve of the problem BuildTrackProblem makes.
SolveReport Solve(const ShapeLookup& lookup, const Track& track, const std::vector<Association>& data,
                  double sigma_scale, const FitOptions& options, ceres::LinearSolverType linear_solver,
                  TrackState* state) {
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  SolveReport report;
  report.num_points = BuildTrackProblem(lookup, track, data, sigma_scale, options, state, &problem);
  ceres::Solver::Options solver_options;
  solver_options.minimizer_type = ceres::TRUST_REGION;
  solver_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver_options.linear_solver_type = linear_solver;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = options.function_tolerance;
  solver_options.gradient_tolerance = options.gradient_tolerance;
  solver_options.parameter_tolerance = options.parameter_tolerance;
  solver_options.num_threads = options.num_threads;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  StopAfterRejectedSteps stop(options.max_rejected_steps);
  if (options.max_rejected_steps > 0) solver_options.callbacks.push_back(&stop);
  ceres::Solver::Summary summary;
  const auto start = std::chrono::steady_clock::now();
  ceres::Solve(solver_options, &problem, &summary);
  report.seconds = Seconds(start);
  report.initial_cost = summary.initial_cost;
  report.final_cost = summary.final_cost;
  report.num_iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  std::vector<double> step_seconds;  // iterations[0] is the initial evaluation, not a step
  for (size_t k = 1; k < summary.iterations.size(); ++k) {
    step_seconds.push_back(summary.iterations[k].iteration_time_in_seconds);
  }
  report.median_step_seconds = Median(step_seconds);
  report.usable = summary.IsSolutionUsable();
  report.termination = std::string(ceres::TerminationTypeToString(summary.termination_type)) + ": " +
                       summary.message;
  for (auto& pose : state->poses) pose[3] = WrapAngle(pose[3]);
  return report;
}

// The first association of every frame (AssociateByDetection); throws when
// no frame has enough points.
std::vector<Association> AssociateByDetections(const Track& track, const FitOptions& options,
                                               const std::string& name) {
  std::vector<Association> data(track.frames.size());
  int frames_with_data = 0;
  for (size_t k = 0; k < track.frames.size(); ++k) {
    data[k] = AssociateByDetection(track.frames[k], options.association_radius, options.data_term);
    frames_with_data += int(data[k].points.size()) >= options.min_points_per_frame;
  }
  SAMP_CHECK(frames_with_data > 0) << name << " has no frame with >= " << options.min_points_per_frame
                                   << " stereo points within " << options.association_radius
                                   << " m of the detection";
  return data;
}

// One EM re-association with the fitted shape and trajectory. The frames
// that keep fewer than min_points_per_frame points are noted in *notes
// ("frame 7: why"). False (and *data unchanged) when no frame keeps enough.
bool Reassociate(const ShapeLookup& lookup, const Track& track, const FitOptions& options,
                 const TrackState& state, std::vector<Association>* data, std::vector<std::string>* notes) {
  const int num_frames = int(track.frames.size());
  std::vector<AlignedBox> boxes(state.codes.size());
  for (size_t c = 0; c < state.codes.size(); ++c) boxes[c] = lookup.InsideBox(state.codes[c]);
  std::vector<Association> refined(num_frames);
  int refined_frames = 0;
  for (int k = 0; k < num_frames; ++k) {
    const int c = options.single_frame ? k : 0;
    const TrackFrame& f = track.frames[k];
    std::string why;
    if (options.data_term == DataTerm::kDisparity) {
      refined[k] = AssociateByResiduals(f, lookup, DataTermOptions(track, f, options, 1.0), state.codes[c],
                                        state.poses[k], options, &why);
    } else if (boxes[c].IsEmpty()) {
      why = "the fitted shape is empty (phi_z >= 0 everywhere)";
    } else {
      refined[k] = AssociateByFit(f, lookup, state.codes[c], state.poses[k], boxes[c], options, &why);
    }
    if (int(refined[k].points.size()) >= options.min_points_per_frame) {
      ++refined_frames;
    } else {
      notes->push_back("frame " + std::to_string(f.frame) + ": " + why);
    }
  }
  if (refined_frames == 0) return false;
  *data = std::move(refined);
  return true;
}

// Frames that moved more than max_position_change from their initial pose
// (diverged) back to it (single-frame mode: and to the mean shape); returns
// their frame numbers.
std::vector<int> ResetDivergedFrames(const Track& track, const InitialState& init, const FitOptions& options,
                                     TrackState* state) {
  std::vector<int> reset_frames;
  for (size_t k = 0; k < track.frames.size(); ++k) {
    if ((state->poses[k].head<3>() - init.poses[k].head<3>()).norm() <= options.max_position_change) continue;
    state->poses[k] = init.poses[k];
    if (options.single_frame) state->codes[k].setZero();
    reset_frames.push_back(track.frames[k].frame);
  }
  return reset_frames;
}

// The fitted frame k as reported, with the data term at the solution over
// the last solve's points.
FrameFit FrameResult(const ShapeLookup& lookup, const Track& track, int k, const Association& association,
                     const TrackState& state, const FitOptions& options) {
  const bool single = options.single_frame;
  FrameFit out;
  const TrackFrame& f = track.frames[k];
  out.frame = f.frame;
  out.time = f.time;
  out.position = state.poses[k].head<3>();
  out.yaw = WrapAngle(state.poses[k][3]);
  out.motion_model = state.models[k];
  const int n = int(association.points.size());
  out.num_points = n >= options.min_points_per_frame ? n : 0;
  const Eigen::VectorXd& z = state.codes[single ? k : 0];
  if (single) out.shape_code = z;
  if (!single) {
    out.speed = state.velocities[k][0];
    out.yaw_rate = state.velocities[k][1];
  }
  if (out.num_points > 0) {
    out.effective_points = EffectivePoints(f, out.num_points, options);
    out.data_cost = FrameDataCost(lookup, track, f, association, z, state.poses[k], options);
    if (options.keep_points) out.points_in_world = association.points;
  }
  return out;
}

// Single-frame mode: velocities by finite differences of the fitted poses (reported only).
void FiniteDifferenceVelocities(std::vector<FrameFit>* frames) {
  const int num_frames = int(frames->size());
  for (int k = 0; k < num_frames; ++k) {
    const int a = std::max(0, k - 1), b = std::min(num_frames - 1, std::max(k, a + 1));
    if (a == b) continue;
    const FrameFit &fa = (*frames)[a], &fb = (*frames)[b];
    const double dt = fb.time - fa.time;
    (*frames)[k].speed = (fb.position - fa.position).norm() / dt;
    (*frames)[k].yaw_rate = WrapAngle(fb.yaw - fa.yaw) / dt;
  }
}

}  // namespace

std::string FitSummary::BriefReport() const {
  std::ostringstream s;
  s << solves.size() << " solve(s), " << num_iterations << " LM iterations, cost "
    << initial_cost << " -> " << final_cost << ", " << seconds * 1e3 << " ms"
    << (usable ? "" : " [NOT USABLE]");
  if (!solves.empty()) s << ", last: " << solves.back().termination;
  if (num_points_behind_camera > 0) s << ", " << num_points_behind_camera << " points behind the camera dropped";
  return s.str();
}

std::string FitSummary::UnusableReason() const {
  if (solves.empty()) return "no solve was run";
  for (size_t k = 0; k < solves.size(); ++k) {
    if (solves[k].usable) continue;
    std::ostringstream s;
    s << "solve " << k + 1 << " of " << solves.size() << (k == 0 ? " (initial)" : " (EM)")
      << " is not usable: " << (solves[k].termination.empty() ? "no termination reported" : solves[k].termination);
    return s.str();
  }
  return "";
}

Eigen::Isometry3d FrameFit::WorldFromObject() const { return samp::WorldFromObject(position, yaw); }

TrackFitter::TrackFitter(const ShapeModel& model, const FitOptions& options)
    : lookup_(model), options_(options) {
  options_.Check();
  linear_solver_ = LinearSolverTypeOf(options_.linear_solver);
}

TrackFit TrackFitter::Fit(const Track& track) const {
  const auto start = std::chrono::steady_clock::now();
  const std::string name = TrackName(track);
  CheckTrack(track, name);
  const int num_frames = int(track.frames.size());
  const int nr = lookup_.num_components();
  const bool single = options_.single_frame;

  const InitialState init = InitializeTrack(track, options_);
  TrackState state;
  state.codes.assign(single ? num_frames : 1, Eigen::VectorXd::Zero(nr));
  state.poses = init.poses;
  state.velocities = init.velocities;
  state.models.assign(num_frames, "none");
  std::vector<Association> data = AssociateByDetections(track, options_, name);

  TrackFit fit;
  fit.track_id = track.id;
  fit.sequence = track.sequence;
  fit.type = track.type;
  fit.single_frame = single;
  FitSummary& summary = fit.summary;
  for (const Association& a : data) summary.num_points_behind_camera += a.behind_camera;
  if (summary.num_points_behind_camera > 0) {
    LogInfo() << name << ": " << summary.num_points_behind_camera
              << " candidate point(s) not in front of the camera dropped (disparity term)";
  }
  const double first_scale = options_.em_iterations > 0 ? options_.em_initial_sigma_scale : 1.0;
  summary.solves.push_back(Solve(lookup_, track, data, first_scale, options_, linear_solver_, &state));
  for (int it = 0; it < options_.em_iterations; ++it) {
    std::vector<std::string> notes;
    const bool refined = Reassociate(lookup_, track, options_, state, &data, &notes);
    summary.association_notes.insert(summary.association_notes.end(), notes.begin(), notes.end());
    if (!refined) {
      std::ostringstream message;
      message << name << ": EM association kept fewer than " << options_.min_points_per_frame
              << " points in every frame; keeping the detection association. Per frame:";
      for (const std::string& note : notes) message << "\n  " << note;
      LogWarning() << message.str();
      break;
    }
    if (!notes.empty()) {
      LogInfo() << name << ": EM association: " << notes.size() << " of " << num_frames
                << " frame(s) without data term (first: " << notes.front() << ")";
    }
    summary.solves.push_back(Solve(lookup_, track, data, 1.0, options_, linear_solver_, &state));
  }

  const std::vector<int> reset_frames = ResetDivergedFrames(track, init, options_, &state);
  summary.num_frames_reset = int(reset_frames.size());
  if (!reset_frames.empty()) {
    std::ostringstream list;
    for (int f : reset_frames) list << " " << f;
    LogWarning() << name << ": " << reset_frames.size() << " frame(s) moved more than "
                 << options_.max_position_change << " m from the detection and were reset to it:" << list.str();
  }

  summary.initial_cost = summary.solves.front().initial_cost;
  summary.final_cost = summary.solves.back().final_cost;
  summary.usable = true;
  for (const SolveReport& s : summary.solves) {
    summary.num_iterations += s.num_iterations;
    summary.usable = summary.usable && s.usable;
  }
  fit.shape_code = single ? Eigen::VectorXd::Zero(nr) : state.codes[0];
  if (single) {
    for (const auto& z : state.codes) fit.shape_code += z / double(num_frames);
  }
  for (int k = 0; k < num_frames; ++k) fit.frames.push_back(FrameResult(lookup_, track, k, data[k], state, options_));
  if (single) FiniteDifferenceVelocities(&fit.frames);
  summary.seconds = Seconds(start);
  if (!summary.usable) LogWarning() << name << ": solver result not usable: " << summary.BriefReport();
  return fit;
}

}  // namespace samp
