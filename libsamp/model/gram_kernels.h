// Between gram.cc and the instruction-set specific kernels (gram_avx2.cc,
// gram_avx512.cc). Declarations only: those translation units are compiled
// with -mavx2/-mavx512f and must share no inline code with the rest of the
// program (an inline function compiled twice with different instruction sets
// is an ODR violation, and the linker may keep the AVX copy for everyone;
// tests/model/check_isa_objects.cmake checks their objects).
#pragma once

#include <cstdint>

namespace samp {
namespace gram_internal {

// Multiplies one packed A panel by `num_panels` consecutive packed B panels
// and adds the products to c:
//   c(i, q * nr + j) += sum_{k < depth} a[k * mr + i] * b[q * depth * nr + k * nr + j]
// for i < min(mr, rows) and q * nr + j < cols (the rest is padding, not
// written). c is column-major with leading dimension ldc. The float sums run
// over `depth` terms, the accumulation into c is in double.
using RowPanelFunction = void (*)(const float* a, const float* b, int64_t depth,
                                  int64_t num_panels, int64_t rows, int64_t cols, double* c,
                                  int64_t ldc);

struct MicroKernel {
  int mr;  // rows of a tile = width of an A panel
  int nr;  // columns of a tile = width of a B panel
  RowPanelFunction row_panel;
};

// Defined in the instruction-set specific translation units; call only when
// the CPU supports the instruction set (GramKernelSupported).
const MicroKernel* Avx2MicroKernel();
const MicroKernel* Avx512MicroKernel();

}  // namespace gram_internal
}  // namespace samp
