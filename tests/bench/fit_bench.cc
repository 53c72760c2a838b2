// Fitter benchmark (docs/benchmarks.md, "## Fitter"): one 21-frame synthetic
// track on a circular arc, 5,000 points per frame, R = 5, one thread.
//   BM_Fit/em:0/compressed:1  one Levenberg-Marquardt solve (analytic per-frame
//                             blocks compressed to R + 5 rows, the default)
//   BM_Fit/em:1/compressed:1  with the hard-EM pass (re-association + second solve)
//   BM_Fit/.../compressed:0   the per-frame blocks with N rows
//   BM_Fit/.../term:N         data term: 0 = the paper's energy (--data-term
//                             paper --weighting mean --huber-loss), 1 = the
//                             default (ray depth, mixture, effective weighting),
//                             2 = the disparity term (effective weighting)
//   BM_Fit/.../cap:N          FitOptions::max_solve_points_per_frame = N
//                             (0 = all 5,000 points of a frame in every solve;
//                             250 = the default)
//   BM_FitWithoutDetectedSize  the default fit with --detection-size-sigma 0
//   BM_FitWithoutDetectedPosition  the default fit with --no-detection-position
//   BM_FitLinearSolver/<solver>  the single solve with other linear solvers
//   BM_FitAutodiffPerPoint       the same single solve with one autodiff
//                                cost block per point (for comparison)
// Counters: ms_per_iteration = wall time of the Ceres solves / LM iterations
// (includes set-up, the initial evaluation and the final pass);
// ms_per_lm_step = median of Ceres' own iteration times over the LM steps;
// lm_iterations per fit; behind_camera (the disparity term) = candidate
// points dropped because they are not in front of the camera (the track
// passes beside the camera), FitSummary::num_points_behind_camera.
// `fit_bench --fit_dump` prints the fit outputs of the BM_Fit configurations
// instead (17 digits), to compare two builds.
#include <benchmark/benchmark.h>
#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "libsamp/core/log.h"
#include "libsamp/data/tracking.h"
#include "libsamp/fit/fitter.h"
#include "libsamp/fit/costs/ground.h"
#include "libsamp/fit/costs/motion.h"
#include "libsamp/fit/costs/shape_prior.h"
#include "tests/fit/fit_test_util.h"

namespace samp {
namespace {

constexpr int kFrames = 21;
constexpr int kPointsPerFrame = 5000;

struct Fixture {
  ShapeModel model = testing::MakeSyntheticModel(5, 0.1);
  ShapeLookup lookup{model};
  testing::Synthetic synthetic = WithDetectionCovariances(
      testing::MakeTrack(lookup, kFrames, 8.0, 0.3, kPointsPerFrame * 20 / 21, 21));

  // As the sequence reader fills them: the detector model's covariances, so
  // that the default fit includes the detected-position term.
  static testing::Synthetic WithDetectionCovariances(testing::Synthetic s) {
    for (TrackFrame& tf : s.track.frames)
      tf.detection_covariance = DetectionCovariance(tf.detection.position, TrackerOptions());
    return s;
  }
};

const Fixture& GetFixture() {
  static const Fixture fixture;
  return fixture;
}

void RunFit(benchmark::State& state, const FitOptions& options) {
  SetLogLevel(LogLevel::kWarning);
  const Fixture& f = GetFixture();
  TrackFitter fitter(f.model, options);
  int iterations = 0, fits = 0, behind_camera = 0;
  double solve_seconds = 0.0;
  std::vector<double> step_seconds;
  for (auto _ : state) {
    const TrackFit fit = fitter.Fit(f.synthetic.track);
    behind_camera = fit.summary.num_points_behind_camera;
    benchmark::DoNotOptimize(fit.shape_code.data());
    iterations += fit.summary.num_iterations;
    for (const auto& s : fit.summary.solves) {
      solve_seconds += s.seconds;
      step_seconds.push_back(s.median_step_seconds);
    }
    ++fits;
    if (!fit.summary.usable) state.SkipWithError("solution not usable");
  }
  state.counters["lm_iterations"] = double(iterations) / fits;
  state.counters["ms_per_iteration"] = 1e3 * solve_seconds / iterations;
  std::sort(step_seconds.begin(), step_seconds.end());
  state.counters["ms_per_lm_step"] = step_seconds.empty() ? 0.0 : 1e3 * step_seconds[step_seconds.size() / 2];
  state.counters["points"] = double(f.synthetic.track.frames[0].candidate_points_in_world.size());
  if (options.data_term == DataTerm::kDisparity) state.counters["behind_camera"] = behind_camera;
}

void BM_Fit(benchmark::State& state) {
  FitOptions options;
  options.em_iterations = int(state.range(0));
  options.compress_data_blocks = state.range(1) != 0;
  const DataTerm terms[] = {DataTerm::kPaper, DataTerm::kRayDepth, DataTerm::kDisparity};
  options.data_term = terms[state.range(2)];
  options.max_solve_points_per_frame = int(state.range(3));
  // term 0 = the paper's energy (mean weighting, Huber, no detected size); 1 = the default
  // (ray depth, effective weighting, mixture); 2 = the disparity term (effective).
  if (options.data_term == DataTerm::kPaper) {
    options.data_weighting = DataWeighting::kMean;
    options.mixture_loss = false;
    options.detection_size_sigma = 0.0;
    options.detection_position = false;
  }
  RunFit(state, options);
}
BENCHMARK(BM_Fit)
    ->ArgNames({"em", "compressed", "term", "cap"})
    ->Args({0, 1, 1, 250})
    ->Args({1, 1, 1, 250})
    ->Args({0, 1, 0, 250})
    ->Args({1, 1, 0, 250})
    ->Args({1, 1, 1, 500})
    ->Args({1, 1, 1, 1000})
    ->Args({0, 1, 1, 0})
    ->Args({1, 1, 1, 0})
    ->Args({0, 1, 0, 0})
    ->Args({1, 1, 0, 0})
    ->Args({0, 0, 0, 0})
    ->Args({1, 0, 0, 0})
    ->Args({0, 1, 2, 0})
    ->Args({1, 1, 2, 0})
    ->Unit(benchmark::kMillisecond);

// The default fit (with the EM pass) without the detected-size term, to
// measure what the term costs (its box linearisations) against BM_Fit/em:1/
// compressed:1/term:1/cap:250 in the same run.
void BM_FitWithoutDetectedSize(benchmark::State& state) {
  FitOptions options;
  options.detection_size_sigma = 0.0;
  RunFit(state, options);
}
BENCHMARK(BM_FitWithoutDetectedSize)->Unit(benchmark::kMillisecond);

// The default fit (with the EM pass) without the detected-position term.
void BM_FitWithoutDetectedPosition(benchmark::State& state) {
  FitOptions options;
  options.detection_position = false;
  RunFit(state, options);
}
BENCHMARK(BM_FitWithoutDetectedPosition)->Unit(benchmark::kMillisecond);

void BM_FitLinearSolver(benchmark::State& state) {
  FitOptions options;
  options.em_iterations = 0;
  options.data_term = DataTerm::kPaper;  // comparable with the earlier figures
  options.max_solve_points_per_frame = 0;
  options.data_weighting = DataWeighting::kMean;
  options.mixture_loss = false;
  const char* solvers[] = {"sparse_normal_cholesky", "dense_schur", "iterative_schur", "dense_qr"};
  options.linear_solver = solvers[state.range(0)];
  state.SetLabel(options.linear_solver);
  RunFit(state, options);
}
BENCHMARK(BM_FitLinearSolver)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);

inline double Scalar(double x) { return x; }
template <int N>
double Scalar(const ceres::Jet<double, N>& x) {
  return x.a;
}

// Per-point autodiff formulation of the same data term: one residual block
// per point, templated trilinear lookup on the model's D x R components.
struct AutodiffPointCost {
  const ShapeModel* model;
  Eigen::Vector3d point;
  double inv_sigma, sqrt_weight, huber;

  template <typename T>
  bool operator()(const T* z, const T* pose, T* residual) const {
    using std::abs;
    using std::cos;
    using std::floor;
    using std::sin;
    using std::sqrt;
    const GridSpec& g = model->grid;
    const T c = cos(pose[3]), s = sin(pose[3]);
    const T dx = point.x() - pose[0], dy = point.y() - pose[1], dz = point.z() - pose[2];
    const T o[3] = {c * dx - s * dz, dy, s * dx + c * dz};
    T q[3], outside_sq = T(0.0);
    int i0[3];
    T f[3];
    const Eigen::Vector3d hi = g.MaxCorner();
    for (int a = 0; a < 3; ++a) {
      q[a] = o[a];
      if (q[a] < T(g.origin[a])) q[a] = T(g.origin[a]);
      if (q[a] > T(hi[a])) q[a] = T(hi[a]);
      const T out = o[a] - q[a];
      outside_sq += out * out;
      const T u = (q[a] - g.origin[a]) / g.voxel_size;
      int i = int(floor(Scalar(u)));
      i = std::min(std::max(i, 0), g.dims[a] - 2);
      i0[a] = i;
      f[a] = u - double(i);
    }
    T value = T(0.0);
    for (int k = 0; k < 8; ++k) {
      const int di = k & 1, dj = (k >> 1) & 1, dk = k >> 2;
      const int64_t v = g.Index(i0[0] + di, i0[1] + dj, i0[2] + dk);
      T corner = T(double(model->mean[v]));
      for (int r = 0; r < model->NumComponents(); ++r) corner += double(model->components(v, r)) * z[r];
      const T w = (di ? f[0] : 1.0 - f[0]) * (dj ? f[1] : 1.0 - f[1]) * (dk ? f[2] : 1.0 - f[2]);
      value += w * corner;
    }
    if (Scalar(outside_sq) > 0.0) value += sqrt(outside_sq);
    const T sv = value * inv_sigma;
    if (abs(sv) <= T(huber)) {
      residual[0] = sqrt_weight * sv;
    } else {
      const T root = sqrt(2.0 * huber * abs(sv) - huber * huber);
      residual[0] = sqrt_weight * (sv > T(0.0) ? root : -root);
    }
    return true;
  }
};

void BM_FitAutodiffPerPoint(benchmark::State& state) {
  SetLogLevel(LogLevel::kWarning);
  const Fixture& f = GetFixture();
  const Track& track = f.synthetic.track;
  FitOptions options;
  options.em_iterations = 0;
  const InitialState init = InitializeTrack(track, options);
  const int n = int(track.frames.size());
  int iterations = 0, fits = 0;
  double solve_seconds = 0.0;
  std::vector<double> step_seconds;
  for (auto _ : state) {
    Eigen::VectorXd z = Eigen::VectorXd::Zero(5);
    std::vector<Eigen::Vector4d> poses = init.poses;
    std::vector<Eigen::Vector2d> velocities = init.velocities;
    ceres::Problem problem;
    problem.AddResidualBlock(ShapePriorCost::Create(f.lookup.sigmas(), 1.0), nullptr, z.data());
    for (int k = 0; k < n; ++k) {
      const TrackFrame& tf = track.frames[k];
      const Eigen::Vector3d centre = tf.world_from_camera * (tf.detection.position - Eigen::Vector3d(0, 0.5 * tf.detection.height, 0));
      std::vector<int> used;
      for (size_t i = 0; i < tf.candidate_points_in_world.size(); ++i)
        if ((tf.candidate_points_in_world[i] - centre).norm() <= options.association_radius) used.push_back(int(i));
      const double sqrt_weight = std::sqrt(1.0 / n / double(used.size()));
      for (int i : used) {
        auto* cost = new ceres::AutoDiffCostFunction<AutodiffPointCost, 1, 5, 4>(new AutodiffPointCost{
            &f.model, tf.candidate_points_in_world[i],
            1.0 / (tf.candidate_sigmas[i] * options.em_initial_sigma_scale), sqrt_weight, options.huber_threshold});
        problem.AddResidualBlock(cost, nullptr, z.data(), poses[k].data());
      }
      problem.AddResidualBlock(GroundCost::Create(tf.ground_plane_in_world, options.sigma_ground, 1.0 / n),
                               nullptr, poses[k].data());
      if (k == 0) continue;
      const double dt = tf.time - track.frames[k - 1].time;
      const MotionModel model = SelectMotionModel(velocities[k - 1][0], velocities[k - 1][1],
                                                  options.standing_speed, options.straight_yaw_rate);
      const auto sigma = MotionCovariance(model, poses[k - 1].data(), velocities[k - 1].data(), dt,
                                          options.motion_noise);
      problem.AddResidualBlock(MotionCost::Create(model, dt, SqrtInformation(sigma), 1.0 / n), nullptr,
                               poses[k - 1].data(), velocities[k - 1].data(), poses[k].data(),
                               velocities[k].data());
    }
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    so.max_num_iterations = options.max_iterations;
    so.function_tolerance = options.function_tolerance;
    so.gradient_tolerance = options.gradient_tolerance;
    so.parameter_tolerance = options.parameter_tolerance;
    so.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    const auto start = std::chrono::steady_clock::now();
    ceres::Solve(so, &problem, &summary);
    solve_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    iterations += summary.num_successful_steps + summary.num_unsuccessful_steps;
    ++fits;
    if (!summary.IsSolutionUsable()) state.SkipWithError("solution not usable");
  }
  state.counters["lm_iterations"] = double(iterations) / fits;
  state.counters["ms_per_iteration"] = 1e3 * solve_seconds / iterations;
  std::sort(step_seconds.begin(), step_seconds.end());
  state.counters["ms_per_lm_step"] = step_seconds.empty() ? 0.0 : 1e3 * step_seconds[step_seconds.size() / 2];
}
BENCHMARK(BM_FitAutodiffPerPoint)->Unit(benchmark::kMillisecond);

// --fit_dump: the fitted code, poses and costs of every BM_Fit configuration
// (one fit each, 17 significant digits), to compare two builds' fit outputs.
void DumpFits() {
  SetLogLevel(LogLevel::kWarning);
  const Fixture& f = GetFixture();
  const int configs[][4] = {{0, 1, 1, 250}, {1, 1, 1, 250}, {0, 1, 0, 250}, {1, 1, 0, 250}, {1, 1, 1, 0},
                            {1, 1, 0, 0},   {1, 0, 1, 250}, {1, 1, 2, 0}};
  for (const auto& c : configs) {
    FitOptions options;
    options.em_iterations = c[0];
    options.compress_data_blocks = c[1] != 0;
    const DataTerm terms[] = {DataTerm::kPaper, DataTerm::kRayDepth, DataTerm::kDisparity};
    options.data_term = terms[c[2]];
    options.max_solve_points_per_frame = c[3];
    if (options.data_term == DataTerm::kPaper) {
      options.data_weighting = DataWeighting::kMean;
      options.mixture_loss = false;
      options.detection_size_sigma = 0.0;
      options.detection_position = false;
    }
    const TrackFit fit = TrackFitter(f.model, options).Fit(f.synthetic.track);
    std::printf("em:%d/compressed:%d/term:%d/cap:%d iterations %d cost %.17g -> %.17g\n  code", c[0], c[1], c[2],
                c[3], fit.summary.num_iterations, fit.summary.initial_cost, fit.summary.final_cost);
    for (int r = 0; r < fit.shape_code.size(); ++r) std::printf(" %.17g", fit.shape_code[r]);
    std::printf("\n");
    for (const FrameFit& ff : fit.frames) {
      std::printf("  frame %d points %d position %.17g %.17g %.17g yaw %.17g data_cost %.17g\n", ff.frame,
                  ff.num_points, ff.position.x(), ff.position.y(), ff.position.z(), ff.yaw, ff.data_cost);
    }
  }
}

}  // namespace
}  // namespace samp

int main(int argc, char** argv) {
  for (int a = 1; a < argc; ++a) {
    if (std::string(argv[a]) == "--fit_dump") {
      samp::DumpFits();
      return 0;
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
