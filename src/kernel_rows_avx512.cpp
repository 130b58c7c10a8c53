// The row kernels compiled for AVX-512 (F, VL, DQ, BW) with 512-bit vectors (this file only;
// chosen at run time when the CPU has them). No Eigen or PCL type crosses this file, so its alignment assumptions cannot leak.
#include "kernel_math.h"
#include "kernel_rows.h"

// GCC 12 reports the undefined first operand that its own avx512fintrin.h passes to the
// rounding and scaling builtins as maybe uninitialized (clang has no such warning group).
#if !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <immintrin.h>

namespace range_nlm
{
namespace detail
{
namespace avx512
{
#include "kernel_rows.inc"
} // namespace avx512

const RowKernels&
avx512RowKernels()
{
  return avx512::kKernels;
}
} // namespace detail
} // namespace range_nlm
