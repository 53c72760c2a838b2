// Benchmarks of the model layer: PCA of N synthetic SDF-sized grids (R = 20)
// and the trilinear lookups of ShapeLookup. Figures: docs/benchmarks.md.
//
//   pca_bench --benchmark_filter=Pca             # PCA, N = 200 / 1000
//   pca_bench --benchmark_filter=Gram            # its Gram product, per kernel
//   pca_bench --benchmark_filter=Evaluate        # lookups, ns per point
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <map>
#include <memory>
#include <random>

#include "libsamp/core/grid_spec.h"
#include "libsamp/model/gram.h"
#include "libsamp/model/pca.h"
#include "libsamp/model/shape_lookup.h"
#include "libsamp/model/shape_model.h"

namespace samp {
namespace {

// N grids of dimension D: 40 planted directions with variances 1/k^2 plus
// small isotropic noise around an SDF-like mean (values of a few metres).
const Eigen::MatrixXf& SyntheticSamples(int64_t dim, int num_samples) {
  static std::map<std::pair<int64_t, int>, std::unique_ptr<Eigen::MatrixXf>> cache;
  auto& slot = cache[{dim, num_samples}];
  if (slot) return *slot;
  std::mt19937 rng(42);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  const int num_planted = 40;
  Eigen::MatrixXf basis(dim, num_planted);
  for (int64_t i = 0; i < basis.size(); ++i) basis.data()[i] = normal(rng) / std::sqrt(float(dim));
  Eigen::MatrixXf coefficients(num_planted, num_samples);
  for (int k = 0; k < num_planted; ++k)
    for (int j = 0; j < num_samples; ++j) coefficients(k, j) = normal(rng) / float(k + 1);
  slot = std::make_unique<Eigen::MatrixXf>(basis * coefficients);
  for (int64_t i = 0; i < slot->size(); ++i) slot->data()[i] += 2.0f + 1e-3f * normal(rng);
  return *slot;
}

// Args: number of samples N, voxel size in mm (grid = GridSpec::CarDefault), threads (0 = all).
void BM_Pca(benchmark::State& state) {
  const int num_samples = int(state.range(0));
  const GridSpec grid = GridSpec::CarDefault(state.range(1) / 1000.0);
  const int threads = int(state.range(2));
  const Eigen::MatrixXf& samples = SyntheticSamples(grid.NumVoxels(), num_samples);
  std::unique_ptr<tbb::global_control> control;
  if (threads > 0) {
    control = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    threads);
  }
  PcaOptions options;
  options.num_components = 20;
  int iterations = 0;
  for (auto _ : state) {
    const PcaResult result = ComputePca(samples, options);
    iterations = result.num_iterations;
    benchmark::DoNotOptimize(result.components.data());
  }
  state.counters["D"] = double(grid.NumVoxels());
  state.counters["N"] = num_samples;
  state.counters["spectra_iterations"] = iterations;
}
BENCHMARK(BM_Pca)
    ->ArgNames({"N", "voxel_mm", "threads"})
    ->Args({200, 100, 1})
    ->Args({200, 100, 0})
    ->Args({1000, 100, 1})
    ->Args({1000, 100, 0})
    ->Args({200, 50, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(3);

// The Gram product alone (libsamp/model/gram.h), per kernel. Args: N, kernel
// (0 portable, 1 AVX2, 2 AVX-512), threads (0 = all). GFLOPS counts the
// 2 D N (N + 1) / 2 flops of the upper triangle (what the kernel must compute).
void BM_Gram(benchmark::State& state) {
  const int num_samples = int(state.range(0));
  const auto kernel = static_cast<GramKernel>(state.range(1));
  const int threads = int(state.range(2));
  if (!GramKernelSupported(kernel)) {
    state.SkipWithError("kernel not supported on this CPU");
    return;
  }
  const GridSpec grid = GridSpec::CarDefault(0.1);
  const int64_t dim = grid.NumVoxels();
  const Eigen::MatrixXf& samples = SyntheticSamples(dim, num_samples);
  const Eigen::VectorXf mean = samples.rowwise().mean();
  std::unique_ptr<tbb::global_control> control;
  if (threads > 0) {
    control = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    threads);
  }
  Eigen::MatrixXd gram(num_samples, num_samples);
  for (auto _ : state) {
    CentredGram(samples.data(), dim, num_samples, mean.data(), gram.data(), kernel);
    benchmark::DoNotOptimize(gram.data());
  }
  const double flops = double(dim) * num_samples * (num_samples + 1);
  state.counters["GFLOPS"] =
      benchmark::Counter(flops * 1e-9 * double(state.iterations()), benchmark::Counter::kIsRate);
  state.SetLabel(GramKernelName(kernel));
}
BENCHMARK(BM_Gram)
    ->ArgNames({"N", "kernel", "threads"})
    ->ArgsProduct({{1000}, {0, 1, 2}, {1, 0}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(3);

ShapeModel BenchmarkModel(int num_components) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  ShapeModel model;
  model.grid = GridSpec::CarDefault(0.1);
  model.mean.resize(model.grid.NumVoxels());
  for (int64_t i = 0; i < model.mean.size(); ++i) model.mean[i] = uniform(rng);
  model.components.resize(model.grid.NumVoxels(), num_components);
  for (int64_t i = 0; i < model.components.size(); ++i) model.components.data()[i] = uniform(rng);
  model.eigenvalues = Eigen::VectorXd::Ones(num_components);
  return model;
}

std::vector<Eigen::Vector3d> CarPoints(int n) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> x(-2.4, 2.4), y(-1.6, 0.1), z(-1.0, 1.0);
  std::vector<Eigen::Vector3d> points(n);
  for (auto& p : points) p = Eigen::Vector3d(x(rng), y(rng), z(rng));
  return points;
}

// Args: R; with gradients d/dpoint and d/dz, from z (8 (R + 1) multiply-adds per point).
void BM_Evaluate(benchmark::State& state) {
  const ShapeLookup lookup(BenchmarkModel(int(state.range(0))));
  const std::vector<Eigen::Vector3d> points = CarPoints(5000);
  const Eigen::VectorXd z = Eigen::VectorXd::Constant(lookup.num_components(), 0.3);
  std::vector<double> d_z(lookup.num_components());
  double d_point[3];
  for (auto _ : state) {
    double sum = 0.0;
    for (const auto& p : points) sum += lookup.Evaluate(z.data(), p.data(), d_point, d_z.data());
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * int64_t(points.size()));
}
BENCHMARK(BM_Evaluate)->ArgName("R")->Arg(5)->Arg(20);

// The fitter's path: the dense grid of z (recomputed every iteration: the code
// alternates) and lookups in it with both gradients.
void BM_EvaluateDense(benchmark::State& state) {
  const ShapeLookup lookup(BenchmarkModel(int(state.range(0))));
  const std::vector<Eigen::Vector3d> points = CarPoints(5000);
  Eigen::VectorXd z = Eigen::VectorXd::Constant(lookup.num_components(), 0.3);
  std::vector<double> d_z(lookup.num_components());
  double d_point[3];
  for (auto _ : state) {
    z[0] = -z[0];
    const double* dense = lookup.DenseCached(z.data());
    double sum = 0.0;
    for (const auto& p : points) sum += lookup.EvaluateDense(dense, p.data(), d_point, d_z.data());
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * int64_t(points.size()));
}
BENCHMARK(BM_EvaluateDense)->ArgName("R")->Arg(5)->Arg(20);

}  // namespace
}  // namespace samp

BENCHMARK_MAIN();
