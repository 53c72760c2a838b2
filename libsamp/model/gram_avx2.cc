// AVX2 + FMA micro-kernel of the Gram products (gram.h). Compiled with
// -mavx2 -mfma; includes nothing but intrinsics and declarations (see
// gram_kernels.h), and everything but the accessor has internal linkage.
#include <immintrin.h>

#include <cstdint>

#include "libsamp/model/gram_kernels.h"

namespace samp {
namespace gram_internal {
namespace {

constexpr int kMr = 16;  // two 8-float registers
constexpr int kNr = 6;   // 12 accumulators + 2 A registers + 1 broadcast <= 16

// c[0..3] += the low four floats of v, c[4..7] += the high four (in double).
__attribute__((always_inline)) inline void AddToDouble(__m256 v, double* c) {
  const __m256d lo = _mm256_cvtps_pd(_mm256_castps256_ps128(v));
  const __m256d hi = _mm256_cvtps_pd(_mm256_extractf128_ps(v, 1));
  _mm256_storeu_pd(c, _mm256_add_pd(_mm256_loadu_pd(c), lo));
  _mm256_storeu_pd(c + 4, _mm256_add_pd(_mm256_loadu_pd(c + 4), hi));
}

void RowPanel(const float* a, const float* b, int64_t depth, int64_t num_panels, int64_t rows,
              int64_t cols, double* c, int64_t ldc) {
  for (int64_t q = 0; q < num_panels; ++q, b += depth * kNr, c += kNr * ldc, cols -= kNr) {
    __m256 acc[kNr][2];
#pragma GCC unroll 6
    for (int j = 0; j < kNr; ++j) acc[j][0] = acc[j][1] = _mm256_setzero_ps();
    const float* ak = a;
    const float* bk = b;
#pragma GCC unroll 2
    for (int64_t k = 0; k < depth; ++k, ak += kMr, bk += kNr) {
      const __m256 a0 = _mm256_loadu_ps(ak);
      const __m256 a1 = _mm256_loadu_ps(ak + 8);
#pragma GCC unroll 6
      for (int j = 0; j < kNr; ++j) {
        const __m256 bj = _mm256_broadcast_ss(bk + j);
        acc[j][0] = _mm256_fmadd_ps(a0, bj, acc[j][0]);
        acc[j][1] = _mm256_fmadd_ps(a1, bj, acc[j][1]);
      }
    }
    const int tile_cols = cols < kNr ? int(cols) : kNr;
    // Constant indices only (unrolled loops), so that acc stays in registers.
    if (rows >= kMr) {
#pragma GCC unroll 6
      for (int j = 0; j < kNr; ++j) {
        if (j < tile_cols) {
          AddToDouble(acc[j][0], c + j * ldc);
          AddToDouble(acc[j][1], c + j * ldc + 8);
        }
      }
    } else {
      alignas(32) float tile[kNr][kMr];
#pragma GCC unroll 6
      for (int j = 0; j < kNr; ++j) {
        _mm256_store_ps(tile[j], acc[j][0]);
        _mm256_store_ps(tile[j] + 8, acc[j][1]);
      }
      for (int j = 0; j < tile_cols; ++j)
        for (int64_t i = 0; i < rows; ++i) c[j * ldc + i] += double(tile[j][i]);
    }
  }
}

constexpr MicroKernel kKernel = {kMr, kNr, &RowPanel};

}  // namespace

const MicroKernel* Avx2MicroKernel() { return &kKernel; }

}  // namespace gram_internal
}  // namespace samp
