// The two products that make up nearly all of the PCA's time (pca.cc), on
// plain pointers: the Gram matrix of the centred samples, Xc^T Xc, and the
// projection Xc P that turns its eigenvectors into principal directions, where
// Xc = X - mean 1^T and X is D x N, column-major (one grid per column).
//
// Both run a register-tiled float kernel over packed panels of Xc: products are
// summed in float over blocks of kGramBlockDepth terms and the block sums in
// double. The kernels for AVX2+FMA and AVX-512 live in their own translation
// units (gram_avx2.cc, gram_avx512.cc) compiled with those instruction sets and
// holding no shared inline code (no Eigen, no std templates), so the rest of the
// program stays baseline x86-64; the kernel is chosen at run time from the CPU's
// features (BestGramKernel). Parallel with TBB over tiles of the output.
// Thread-safe (no shared state).
#pragma once

#include <cstdint>

namespace samp {

// Depth (number of summed products) of the float partial sums.
constexpr int64_t kGramBlockDepth = 512;

enum class GramKernel {
  kPortable,  // plain C++, whatever the baseline compiler flags vectorise it to
  kAvx2,      // AVX2 + FMA, 16 x 6 float tiles
  kAvx512,    // AVX-512F, 32 x 12 float tiles
};

// "portable", "avx2", "avx512".
const char* GramKernelName(GramKernel kernel);

// True when `kernel` is compiled into this build and the CPU (and OS) support it.
bool GramKernelSupported(GramKernel kernel);

// The fastest supported kernel: AVX-512, else AVX2, else portable.
GramKernel BestGramKernel();

// gram (N x N, column-major, leading dimension N) = Xc^T Xc, i.e.
//   gram(i, j) = sum_d (x(d, i) - mean(d)) (x(d, j) - mean(d)),
// both triangles (only the upper one is computed, then mirrored).
// x: D x N column-major, leading dimension D; mean: D values. The centred
// values are formed in float (as x - mean). Throws samp::Error on bad sizes or
// an unsupported kernel.
void CentredGram(const float* x, int64_t dim, int64_t num_samples, const float* mean,
                 double* gram, GramKernel kernel);

// out (D x C, column-major, leading dimension D) = Xc P with p (N x C,
// column-major, leading dimension N), i.e.
//   out(d, c) = sum_n (x(d, n) - mean(d)) p(n, c).
// p is rounded to float for the kernel; sums as in CentredGram.
void CentredProduct(const float* x, int64_t dim, int64_t num_samples, const float* mean,
                    const double* p, int64_t num_cols, double* out, GramKernel kernel);

}  // namespace samp
