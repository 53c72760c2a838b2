// AVX-512F micro-kernel of the Gram products (gram.h). Compiled with
// -mavx512f -mavx2 -mfma; includes nothing but intrinsics and declarations (see
// gram_kernels.h), and everything but the accessor has internal linkage.
#include <immintrin.h>

// GCC 12 reports the self-initialised _mm512_undefined_pd() inside
// _mm512_cvtps_pd / _mm512_extractf64x4_pd as maybe-uninitialised (a known
// false positive of its headers).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#include <cstdint>

#include "libsamp/model/gram_kernels.h"

namespace samp {
namespace gram_internal {
namespace {

constexpr int kMr = 32;  // two 16-float registers
constexpr int kNr = 12;  // 24 accumulators + 2 A registers + 1 broadcast <= 32

// c[0..7] += the low eight floats of v, c[8..15] += the high eight (in double).
__attribute__((always_inline)) inline void AddToDouble(__m512 v, double* c) {
  const __m512d lo = _mm512_cvtps_pd(_mm512_castps512_ps256(v));
  const __m512d hi =
      _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd(_mm512_castps_pd(v), 1)));
  _mm512_storeu_pd(c, _mm512_add_pd(_mm512_loadu_pd(c), lo));
  _mm512_storeu_pd(c + 8, _mm512_add_pd(_mm512_loadu_pd(c + 8), hi));
}

void RowPanel(const float* a, const float* b, int64_t depth, int64_t num_panels, int64_t rows,
              int64_t cols, double* c, int64_t ldc) {
  for (int64_t q = 0; q < num_panels; ++q, b += depth * kNr, c += kNr * ldc, cols -= kNr) {
    __m512 acc[kNr][2];
#pragma GCC unroll 12
    for (int j = 0; j < kNr; ++j) acc[j][0] = acc[j][1] = _mm512_setzero_ps();
    const float* ak = a;
    const float* bk = b;
    for (int64_t k = 0; k < depth; ++k, ak += kMr, bk += kNr) {
      const __m512 a0 = _mm512_loadu_ps(ak);
      const __m512 a1 = _mm512_loadu_ps(ak + 16);
#pragma GCC unroll 12
      for (int j = 0; j < kNr; ++j) {
        const __m512 bj = _mm512_set1_ps(bk[j]);
        acc[j][0] = _mm512_fmadd_ps(a0, bj, acc[j][0]);
        acc[j][1] = _mm512_fmadd_ps(a1, bj, acc[j][1]);
      }
    }
    const int tile_cols = cols < kNr ? int(cols) : kNr;
    // Constant indices only (unrolled loops), so that acc stays in registers.
    if (rows >= kMr) {
#pragma GCC unroll 12
      for (int j = 0; j < kNr; ++j) {
        if (j < tile_cols) {
          AddToDouble(acc[j][0], c + j * ldc);
          AddToDouble(acc[j][1], c + j * ldc + 16);
        }
      }
    } else {
      alignas(64) float tile[kNr][kMr];
#pragma GCC unroll 12
      for (int j = 0; j < kNr; ++j) {
        _mm512_store_ps(tile[j], acc[j][0]);
        _mm512_store_ps(tile[j] + 16, acc[j][1]);
      }
      for (int j = 0; j < tile_cols; ++j)
        for (int64_t i = 0; i < rows; ++i) c[j * ldc + i] += double(tile[j][i]);
    }
  }
}

constexpr MicroKernel kKernel = {kMr, kNr, &RowPanel};

}  // namespace

const MicroKernel* Avx512MicroKernel() { return &kKernel; }

}  // namespace gram_internal
}  // namespace samp
