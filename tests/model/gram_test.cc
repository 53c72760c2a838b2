// The blocked Gram products of the PCA (libsamp/model/gram.h) against
// straightforward double products, for every kernel this CPU supports, on
// sizes that are not multiples of the tiles or of the float block depth.
#include "libsamp/model/gram.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "libsamp/core/error.h"

namespace samp {
namespace {

// D x N column-major samples around an SDF-like mean of a few metres (the
// centring happens in float inside the kernel), and their float mean.
struct Samples {
  int64_t dim = 0;
  int64_t num_samples = 0;
  std::vector<float> x;
  std::vector<float> mean;
};

Samples MakeSamples(int64_t dim, int64_t num_samples, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Samples s;
  s.dim = dim;
  s.num_samples = num_samples;
  s.x.resize(dim * num_samples);
  std::vector<double> offset(dim);
  for (auto& o : offset) o = 3.0 + normal(rng);
  for (int64_t n = 0; n < num_samples; ++n)
    for (int64_t d = 0; d < dim; ++d) s.x[n * dim + d] = float(offset[d] + 0.1 * normal(rng));
  s.mean.resize(dim);
  for (int64_t d = 0; d < dim; ++d) {
    double sum = 0.0;
    for (int64_t n = 0; n < num_samples; ++n) sum += s.x[n * dim + d];
    s.mean[d] = float(sum / double(num_samples));
  }
  return s;
}

double Centred(const Samples& s, int64_t d, int64_t n) {
  return double(s.x[n * s.dim + d]) - double(s.mean[d]);
}

std::vector<double> ReferenceGram(const Samples& s) {
  const int64_t n = s.num_samples;
  std::vector<double> gram(n * n, 0.0);
  for (int64_t j = 0; j < n; ++j)
    for (int64_t i = 0; i < n; ++i) {
      double sum = 0.0;
      for (int64_t d = 0; d < s.dim; ++d) sum += Centred(s, d, i) * Centred(s, d, j);
      gram[j * n + i] = sum;
    }
  return gram;
}

const std::vector<GramKernel>& AllKernels() {
  static const std::vector<GramKernel> kernels = {GramKernel::kPortable, GramKernel::kAvx2,
                                                  GramKernel::kAvx512};
  return kernels;
}

class GramKernelTest : public ::testing::TestWithParam<GramKernel> {
 protected:
  void SetUp() override {
    if (!GramKernelSupported(GetParam())) {
      GTEST_SKIP() << "kernel " << GramKernelName(GetParam()) << " not supported here";
    }
  }
};

TEST_P(GramKernelTest, GramMatchesDoubleProductOnOddSizes) {
  // (D, N): D around the block depth 512 and off it, N = 1, N off every
  // micro-tile size (8/16/32 rows, 4/6/12 columns), over several of the
  // 128 x 240 parallel tiles, and D over several passes of 16 blocks.
  const std::vector<std::pair<int64_t, int64_t>> sizes = {
      {1, 1},    {7, 1},     {300, 1},   {1, 2},     {5, 3},      {255, 5},  {512, 13},
      {513, 17}, {1023, 31}, {1537, 33}, {100, 37},  {1000, 61},  {2000, 100},
      {300, 129}, {600, 241}, {700, 301}, {8193, 7}, {17000, 50}};
  unsigned seed = 1;
  for (const auto& [dim, n] : sizes) {
    SCOPED_TRACE("D = " + std::to_string(dim) + ", N = " + std::to_string(n));
    const Samples s = MakeSamples(dim, n, seed++);
    const std::vector<double> expected = ReferenceGram(s);
    std::vector<double> gram(n * n, -1.0);
    CentredGram(s.x.data(), dim, n, s.mean.data(), gram.data(), GetParam());
    double worst = 0.0;
    for (int64_t j = 0; j < n; ++j) {
      for (int64_t i = 0; i < n; ++i) {
        // Relative to the Cauchy-Schwarz bound of the entry.
        const double scale = std::sqrt(expected[i * n + i] * expected[j * n + j]) + 1e-30;
        worst = std::max(worst, std::abs(gram[j * n + i] - expected[j * n + i]) / scale);
        ASSERT_EQ(gram[j * n + i], gram[i * n + j]) << "not symmetric at " << i << ", " << j;
      }
    }
    EXPECT_LT(worst, 2e-6);
  }
}

TEST_P(GramKernelTest, ProductMatchesDoubleProductOnOddSizes) {
  // (D, N, C): N around the block depth 512, C off the tile widths.
  struct Size {
    int64_t dim, num_samples, num_cols;
  };
  const std::vector<Size> sizes = {{1, 1, 1},     {17, 3, 5},    {300, 2, 20},
                                   {257, 511, 7}, {513, 513, 13}, {1031, 1100, 20}};
  unsigned seed = 100;
  for (const Size& size : sizes) {
    SCOPED_TRACE("D = " + std::to_string(size.dim) + ", N = " + std::to_string(size.num_samples) +
                 ", C = " + std::to_string(size.num_cols));
    const Samples s = MakeSamples(size.dim, size.num_samples, seed++);
    std::mt19937 rng(seed++);
    std::normal_distribution<double> normal(0.0, 1.0);
    std::vector<double> p(size.num_samples * size.num_cols);
    for (auto& v : p) v = normal(rng);
    std::vector<double> out(size.dim * size.num_cols, -1.0);
    CentredProduct(s.x.data(), size.dim, size.num_samples, s.mean.data(), p.data(),
                   size.num_cols, out.data(), GetParam());
    double worst = 0.0;
    for (int64_t c = 0; c < size.num_cols; ++c) {
      for (int64_t d = 0; d < size.dim; ++d) {
        double sum = 0.0, x_norm = 0.0, p_norm = 0.0;
        for (int64_t n = 0; n < size.num_samples; ++n) {
          const double xc = Centred(s, d, n);
          const double pn = p[c * size.num_samples + n];
          sum += xc * pn;
          x_norm += xc * xc;
          p_norm += pn * pn;
        }
        const double scale = std::sqrt(x_norm * p_norm) + 1e-30;
        worst = std::max(worst, std::abs(out[c * size.dim + d] - sum) / scale);
      }
    }
    EXPECT_LT(worst, 2e-6);
  }
}

INSTANTIATE_TEST_SUITE_P(Kernels, GramKernelTest, ::testing::ValuesIn(AllKernels()),
                         [](const ::testing::TestParamInfo<GramKernel>& info) {
                           return std::string(GramKernelName(info.param));
                         });

TEST(GramKernel, AvxKernelsAgreeBitForBit) {
  // AVX2 and AVX-512 sum the same products in the same order (one FMA chain
  // per entry and block, blocks added in order), so they agree exactly.
  if (!GramKernelSupported(GramKernel::kAvx2) || !GramKernelSupported(GramKernel::kAvx512)) {
    GTEST_SKIP() << "needs both AVX2 and AVX-512";
  }
  const Samples s = MakeSamples(1300, 250, 9);
  const int64_t n = s.num_samples;
  std::vector<double> avx2(n * n), avx512(n * n);
  CentredGram(s.x.data(), s.dim, n, s.mean.data(), avx2.data(), GramKernel::kAvx2);
  CentredGram(s.x.data(), s.dim, n, s.mean.data(), avx512.data(), GramKernel::kAvx512);
  EXPECT_EQ(avx2, avx512);
}

TEST(GramKernel, BestIsSupportedAndPrefersWiderVectors) {
  const GramKernel best = BestGramKernel();
  EXPECT_TRUE(GramKernelSupported(best));
  EXPECT_TRUE(GramKernelSupported(GramKernel::kPortable));
  if (GramKernelSupported(GramKernel::kAvx512)) {
    EXPECT_EQ(best, GramKernel::kAvx512);
  } else if (GramKernelSupported(GramKernel::kAvx2)) {
    EXPECT_EQ(best, GramKernel::kAvx2);
  } else {
    EXPECT_EQ(best, GramKernel::kPortable);
  }
  std::cout << "[          ] best Gram kernel here: " << GramKernelName(best) << "\n";
}

TEST(GramKernel, RejectsBadSizes) {
  const float x[2] = {1.0f, 2.0f};
  const float mean[2] = {0.0f, 0.0f};
  double out[4];
  EXPECT_THROW(CentredGram(x, 0, 1, mean, out, GramKernel::kPortable), Error);
  EXPECT_THROW(CentredGram(x, 2, 0, mean, out, GramKernel::kPortable), Error);
  const double p[1] = {1.0};
  EXPECT_THROW(CentredProduct(x, 2, 1, mean, p, 0, out, GramKernel::kPortable), Error);
}

}  // namespace
}  // namespace samp
