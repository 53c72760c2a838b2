// Blocked Gram products (gram.h): packing, the portable micro-kernel, the
// run-time choice of kernel and the TBB drivers. Baseline instruction set; the
// AVX kernels are reached only through gram_kernels.h.
#include "libsamp/model/gram.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <utility>
#include <vector>

#include "libsamp/core/error.h"
#include "libsamp/model/gram_kernels.h"

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

namespace samp {
namespace {

using gram_internal::MicroKernel;

// ---------------------------------------------------------------------------
// Portable micro-kernel: 8 x 4 tiles in plain C++ (SSE2 vectorises the rows).

constexpr int kPortableMr = 8;
constexpr int kPortableNr = 4;

void PortableRowPanel(const float* a, const float* b, int64_t depth, int64_t num_panels,
                      int64_t rows, int64_t cols, double* c, int64_t ldc) {
  for (int64_t q = 0; q < num_panels; ++q, b += depth * kPortableNr, c += kPortableNr * ldc,
               cols -= kPortableNr) {
    float acc[kPortableNr][kPortableMr] = {};
    const float* ak = a;
    const float* bk = b;
    for (int64_t k = 0; k < depth; ++k, ak += kPortableMr, bk += kPortableNr) {
      for (int j = 0; j < kPortableNr; ++j) {
        const float bj = bk[j];
        for (int i = 0; i < kPortableMr; ++i) acc[j][i] += ak[i] * bj;
      }
    }
    const int64_t tile_rows = std::min<int64_t>(rows, kPortableMr);
    const int64_t tile_cols = std::min<int64_t>(cols, kPortableNr);
    for (int64_t j = 0; j < tile_cols; ++j)
      for (int64_t i = 0; i < tile_rows; ++i) c[j * ldc + i] += double(acc[j][i]);
  }
}

constexpr MicroKernel kPortableKernel = {kPortableMr, kPortableNr, &PortableRowPanel};

const MicroKernel& SelectMicroKernel(GramKernel kernel) {
  switch (kernel) {
#if defined(SAMP_GRAM_X86_KERNELS)
    case GramKernel::kAvx2:
      return *gram_internal::Avx2MicroKernel();
    case GramKernel::kAvx512:
      return *gram_internal::Avx512MicroKernel();
#endif
    default:
      return kPortableKernel;
  }
}

// ---------------------------------------------------------------------------
// Packed panels.

// A float buffer aligned to a cache line (the kernels load 32/64-byte vectors).
class AlignedFloats {
 public:
  AlignedFloats() = default;
  explicit AlignedFloats(int64_t size) { Resize(size); }
  void Resize(int64_t size) {
    if (size <= capacity_) return;
    const size_t bytes = (size_t(size) * sizeof(float) + 63) / 64 * 64;
    data_.reset(static_cast<float*>(std::aligned_alloc(64, bytes)));
    SAMP_CHECK(data_ != nullptr) << "Gram: cannot allocate " << bytes << " bytes";
    capacity_ = size;
  }
  float* data() { return data_.get(); }

 private:
  struct Free {
    void operator()(float* p) const { std::free(p); }
  };
  std::unique_ptr<float[], Free> data_;
  int64_t capacity_ = 0;
};

// Upper bound of the kernels' mr and nr (checked in GetMicroKernel).
constexpr int kMaxPanelWidth = 64;

// Tiles of the Gram matrix per parallel task: multiples of every kernel's mr
// (8, 16, 32) and nr (4, 6, 12) respectively.
constexpr int64_t kTileRows = 128;
constexpr int64_t kTileCols = 240;

// Packed panels per pass over the rows: at most this many bytes (in L3) and
// this many blocks of kGramBlockDepth rows.
constexpr int64_t kPackBudgetBytes = int64_t(16) << 20;
constexpr int64_t kMaxBlocksPerPass = 16;

int64_t CeilDiv(int64_t a, int64_t b) { return (a + b - 1) / b; }

// Panel of `width` samples starting at sample i0, rows [d0, d0 + depth), for
// the Gram matrix: out[k * width + c] = x(d0 + k, i0 + c) - mean(d0 + k), zero
// for samples >= num_samples. Groups of four columns are transposed in 4 x 4
// blocks (SSE, part of x86-64), which also keeps four reads in flight.
void PackSamplePanel(const float* x, int64_t dim, int64_t num_samples, const float* mean,
                     int64_t d0, int64_t depth, int64_t i0, int width, float* out) {
  const float* m = mean + d0;
  const int valid = int(std::clamp<int64_t>(num_samples - i0, 0, width));
  int c0 = 0;
#if defined(__SSE2__)
  const int64_t depth4 = depth / 4 * 4;
  for (; c0 + 4 <= valid; c0 += 4) {
    const float* col0 = x + (i0 + c0) * dim + d0;
    const float* col1 = col0 + dim;
    const float* col2 = col1 + dim;
    const float* col3 = col2 + dim;
    float* o = out + c0;
    for (int64_t k = 0; k < depth4; k += 4) {
      const __m128 mk = _mm_loadu_ps(m + k);
      __m128 r0 = _mm_sub_ps(_mm_loadu_ps(col0 + k), mk);
      __m128 r1 = _mm_sub_ps(_mm_loadu_ps(col1 + k), mk);
      __m128 r2 = _mm_sub_ps(_mm_loadu_ps(col2 + k), mk);
      __m128 r3 = _mm_sub_ps(_mm_loadu_ps(col3 + k), mk);
      _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
      _mm_storeu_ps(o + (k + 0) * width, r0);
      _mm_storeu_ps(o + (k + 1) * width, r1);
      _mm_storeu_ps(o + (k + 2) * width, r2);
      _mm_storeu_ps(o + (k + 3) * width, r3);
    }
    for (int64_t k = depth4; k < depth; ++k) {
      o[k * width + 0] = col0[k] - m[k];
      o[k * width + 1] = col1[k] - m[k];
      o[k * width + 2] = col2[k] - m[k];
      o[k * width + 3] = col3[k] - m[k];
    }
  }
#endif
  // Remaining columns (and padding), row by row.
  if (c0 < width) {
    const float* columns[kMaxPanelWidth];
    for (int c = c0; c < valid; ++c) columns[c] = x + (i0 + c) * dim + d0;
    for (int64_t k = 0; k < depth; ++k) {
      float* o = out + k * width;
      for (int c = c0; c < valid; ++c) o[c] = columns[c][k] - m[k];
      for (int c = std::max(c0, valid); c < width; ++c) o[c] = 0.0f;
    }
  }
}

// Row panels of `width` rows from r_begin to r_end, samples [n0, n0 + depth),
// for the projection: panel a holds out[a * depth * width + k * width + i] =
// x(r_begin + a * width + i, n0 + k) - mean(r_begin + a * width + i), zero
// for rows >= r_end. Sample by sample, so each read is one contiguous run of
// x, prefetched a few samples ahead.
void PackRowPanels(const float* x, int64_t dim, const float* mean, int64_t r_begin,
                   int64_t r_end, int64_t n0, int64_t depth, int width, float* out) {
  constexpr int64_t kPrefetchAhead = 4;
  constexpr int64_t kLineFloats = 64 / sizeof(float);
  const int64_t num_panels = CeilDiv(r_end - r_begin, width);
  const float* m = mean + r_begin;
  for (int64_t k = 0; k < depth; ++k) {
    if (k + kPrefetchAhead < depth) {
      const float* ahead = x + (n0 + k + kPrefetchAhead) * dim + r_begin;
      for (int64_t i = 0; i < r_end - r_begin; i += kLineFloats) {
        __builtin_prefetch(ahead + i, 0, 3);
      }
    }
    const float* column = x + (n0 + k) * dim + r_begin;
    for (int64_t a = 0; a < num_panels; ++a) {
      const int64_t i0 = a * width;
      const int rows = int(std::min<int64_t>(width, r_end - r_begin - i0));
      float* o = out + a * depth * width + k * width;
      for (int i = 0; i < rows; ++i) o[i] = column[i0 + i] - m[i0 + i];
      for (int i = rows; i < width; ++i) o[i] = 0.0f;
    }
  }
}

const MicroKernel& GetMicroKernel(GramKernel kernel) {
  SAMP_CHECK(GramKernelSupported(kernel))
      << "Gram kernel '" << GramKernelName(kernel) << "' is not supported on this CPU/build";
  const MicroKernel& micro = SelectMicroKernel(kernel);
  SAMP_CHECK(micro.mr >= 1 && micro.nr >= 1 && micro.mr <= kMaxPanelWidth &&
             micro.nr <= kMaxPanelWidth && kTileRows % micro.mr == 0 &&
             kTileCols % micro.nr == 0)
      << "Gram kernel '" << GramKernelName(kernel) << "': bad tile " << micro.mr << " x "
      << micro.nr;
  return micro;
}

}  // namespace

const char* GramKernelName(GramKernel kernel) {
  switch (kernel) {
    case GramKernel::kPortable:
      return "portable";
    case GramKernel::kAvx2:
      return "avx2";
    case GramKernel::kAvx512:
      return "avx512";
  }
  return "unknown";
}

bool GramKernelSupported(GramKernel kernel) {
  switch (kernel) {
    case GramKernel::kPortable:
      return true;
#if defined(SAMP_GRAM_X86_KERNELS)
    case GramKernel::kAvx2:
      __builtin_cpu_init();
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    case GramKernel::kAvx512:
      __builtin_cpu_init();
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx2") &&
             __builtin_cpu_supports("fma");
#endif
    default:
      return false;
  }
}

GramKernel BestGramKernel() {
  for (GramKernel kernel : {GramKernel::kAvx512, GramKernel::kAvx2}) {
    if (GramKernelSupported(kernel)) return kernel;
  }
  return GramKernel::kPortable;
}

void CentredGram(const float* x, int64_t dim, int64_t num_samples, const float* mean,
                 double* gram, GramKernel kernel) {
  SAMP_CHECK(dim >= 1 && num_samples >= 1)
      << "CentredGram: bad sizes D = " << dim << ", N = " << num_samples;
  const MicroKernel& micro = GetMicroKernel(kernel);
  const int64_t n = num_samples;
  std::fill(gram, gram + n * n, 0.0);

  // Rows are taken in super-blocks of up to kMaxBlocksPerPass blocks of
  // kGramBlockDepth rows (packed data within kPackBudgetBytes): pack the
  // centred rows of every sample twice (A panels of mr samples, B panels of
  // nr samples; long contiguous reads of each column), then multiply the
  // panels tile by tile of the upper triangle, block by block. Two parallel
  // phases per super-block, so few barriers (a barrier costs a whole time
  // slice when another process shares the core). Each entry of the Gram
  // matrix is read and written once per block.
  const int64_t num_a = CeilDiv(n, micro.mr);
  const int64_t num_b = CeilDiv(n, micro.nr);
  const int64_t a_block = num_a * micro.mr * kGramBlockDepth;  // floats per block
  const int64_t b_block = num_b * micro.nr * kGramBlockDepth;
  const int64_t blocks_per_pass = std::clamp<int64_t>(
      kPackBudgetBytes / (int64_t(sizeof(float)) * (a_block + b_block)), 1, kMaxBlocksPerPass);
  const int64_t pass_rows = blocks_per_pass * kGramBlockDepth;
  AlignedFloats a_packed(std::min(blocks_per_pass, CeilDiv(dim, kGramBlockDepth)) * a_block);
  AlignedFloats b_packed(std::min(blocks_per_pass, CeilDiv(dim, kGramBlockDepth)) * b_block);
  // Tiles of kTileRows x kTileCols of the Gram matrix on or above the
  // diagonal, the unit of parallel work: a tile's B panels of one block
  // (<= 480 KB) stay in L2 while its A panels pass over them.
  std::vector<std::pair<int64_t, int64_t>> tiles;
  for (int64_t tj = 0; tj * kTileCols < n; ++tj)
    for (int64_t ti = 0; ti * kTileRows < std::min(n, (tj + 1) * kTileCols); ++ti)
      tiles.emplace_back(ti, tj);
  for (int64_t pass0 = 0; pass0 < dim; pass0 += pass_rows) {
    const int64_t num_blocks = CeilDiv(std::min(pass_rows, dim - pass0), kGramBlockDepth);
    tbb::parallel_for(
        tbb::blocked_range<int64_t>(0, num_a + num_b, 4),
        [&](const tbb::blocked_range<int64_t>& range) {
          for (int64_t p = range.begin(); p != range.end(); ++p) {
            for (int64_t block = 0; block < num_blocks; ++block) {
              const int64_t d0 = pass0 + block * kGramBlockDepth;
              const int64_t depth = std::min(kGramBlockDepth, dim - d0);
              if (p < num_a) {
                PackSamplePanel(x, dim, n, mean, d0, depth, p * micro.mr, micro.mr,
                                a_packed.data() + block * a_block + p * micro.mr * depth);
              } else {
                const int64_t q = p - num_a;
                PackSamplePanel(x, dim, n, mean, d0, depth, q * micro.nr, micro.nr,
                                b_packed.data() + block * b_block + q * micro.nr * depth);
              }
            }
          }
        });
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, tiles.size(), 1),
        [&](const tbb::blocked_range<size_t>& range) {
          for (size_t t = range.begin(); t != range.end(); ++t) {
            const int64_t i_begin = tiles[t].first * kTileRows;
            const int64_t i_end = std::min(n, i_begin + kTileRows);
            const int64_t j_begin = tiles[t].second * kTileCols;
            const int64_t j_end = std::min(n, j_begin + kTileCols);
            const int64_t q_end = CeilDiv(j_end, micro.nr);
            for (int64_t block = 0; block < num_blocks; ++block) {
              const int64_t depth =
                  std::min(kGramBlockDepth, dim - pass0 - block * kGramBlockDepth);
              const float* a = a_packed.data() + block * a_block;
              const float* b = b_packed.data() + block * b_block;
              for (int64_t i0 = i_begin; i0 < i_end; i0 += micro.mr) {
                const int64_t q0 = std::max(j_begin, i0) / micro.nr;  // first with i <= j
                if (q0 >= q_end) break;
                const int64_t j0 = q0 * micro.nr;
                micro.row_panel(a + i0 * depth, b + j0 * depth, depth, q_end - q0, n - i0,
                                n - j0, gram + j0 * n + i0, n);
              }
            }
          }
        });
  }
  // Tiles crossing the diagonal also filled some of the lower triangle; the
  // upper one (i <= j) is complete: mirror it.
  for (int64_t j = 0; j < n; ++j)
    for (int64_t i = j + 1; i < n; ++i) gram[j * n + i] = gram[i * n + j];
}

void CentredProduct(const float* x, int64_t dim, int64_t num_samples, const float* mean,
                    const double* p, int64_t num_cols, double* out, GramKernel kernel) {
  SAMP_CHECK(dim >= 1 && num_samples >= 1 && num_cols >= 1)
      << "CentredProduct: bad sizes D = " << dim << ", N = " << num_samples
      << ", C = " << num_cols;
  const MicroKernel& micro = GetMicroKernel(kernel);
  std::fill(out, out + dim * num_cols, 0.0);

  // B panels: p in float, per block of kGramBlockDepth samples, all blocks
  // one after the other (block n0 starts at n0 * num_b * nr).
  const int64_t num_b = CeilDiv(num_cols, micro.nr);
  AlignedFloats b_packed(num_samples * num_b * micro.nr);
  for (int64_t n0 = 0; n0 < num_samples; n0 += kGramBlockDepth) {
    const int64_t depth = std::min(kGramBlockDepth, num_samples - n0);
    float* block = b_packed.data() + n0 * num_b * micro.nr;
    for (int64_t q = 0; q < num_b; ++q) {
      float* panel = block + q * depth * micro.nr;
      for (int64_t k = 0; k < depth; ++k) {
        for (int j = 0; j < micro.nr; ++j) {
          const int64_t column = q * micro.nr + j;
          panel[k * micro.nr + j] =
              column < num_cols ? float(p[column * num_samples + n0 + k]) : 0.0f;
        }
      }
    }
  }

  // TBB over blocks of kRows rows of `out` (disjoint outputs); per block and
  // per block of samples, pack the A panels (contiguous reads of x) and run
  // each over all B panels.
  constexpr int64_t kRows = 256;
  const int64_t panels_per_block = CeilDiv(kRows, micro.mr);
  tbb::enumerable_thread_specific<AlignedFloats> buffers;
  tbb::parallel_for(
      tbb::blocked_range<int64_t>(0, CeilDiv(dim, kRows), 1),
      [&](const tbb::blocked_range<int64_t>& range) {
        AlignedFloats& a_packed = buffers.local();
        a_packed.Resize(panels_per_block * micro.mr * kGramBlockDepth);
        for (int64_t block = range.begin(); block != range.end(); ++block) {
          const int64_t r_begin = block * kRows;
          const int64_t r_end = std::min(dim, r_begin + kRows);
          const int64_t num_panels = CeilDiv(r_end - r_begin, micro.mr);
          for (int64_t n0 = 0; n0 < num_samples; n0 += kGramBlockDepth) {
            const int64_t depth = std::min(kGramBlockDepth, num_samples - n0);
            PackRowPanels(x, dim, mean, r_begin, r_end, n0, depth, micro.mr, a_packed.data());
            const float* b_block = b_packed.data() + n0 * num_b * micro.nr;
            for (int64_t a = 0; a < num_panels; ++a) {
              const int64_t r0 = r_begin + a * micro.mr;
              micro.row_panel(a_packed.data() + a * micro.mr * depth, b_block, depth, num_b,
                              dim - r0, num_cols, out + r0, dim);
            }
          }
        }
      });
}

}  // namespace samp
