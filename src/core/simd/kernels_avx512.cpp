// The SIMD kernels compiled for AVX-512 (F, VL, DQ, BW) with 512-bit vectors (this file only;
// chosen at run time when the CPU has them).
// No Eigen or PCL type crosses this file, so its alignment assumptions cannot leak.
#include "../fast_math.h"
#include "kernels.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

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
namespace rows
{
#include "row_kernels.inc"
#include "window_kernel.inc"
} // namespace rows
namespace plane_fits
{
#include "plane_fit_kernels.inc"
} // namespace plane_fits
} // namespace avx512

const SimdKernels&
avx512Kernels()
{
  static const SimdKernels kernels{
    {&avx512::rows::moments, &avx512::rows::window_smoothing, &avx512::rows::window_row, &avx512::rows::window_scratch,
     &avx512::rows::window_row_spread},
    avx512::plane_fits::kPlaneFitKernels};
  return kernels;
}

} // namespace detail
} // namespace range_nlm
