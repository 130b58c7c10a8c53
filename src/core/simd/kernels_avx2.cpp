// The SIMD kernels compiled for AVX2 + FMA (this file only; chosen at run time when the CPU has
// them).
// No Eigen or PCL type crosses this file, so its alignment assumptions cannot leak.
#include "../fast_math.h"
#include "kernels.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace range_nlm
{
namespace detail
{
namespace avx2
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
} // namespace avx2

const SimdKernels&
avx2Kernels()
{
  static const SimdKernels kernels{
    {&avx2::rows::moments, &avx2::rows::window_smoothing, &avx2::rows::window_row, &avx2::rows::window_scratch,
     &avx2::rows::window_row_spread},
    avx2::plane_fits::kPlaneFitKernels};
  return kernels;
}

} // namespace detail
} // namespace range_nlm
