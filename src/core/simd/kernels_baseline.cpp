// The SIMD kernels compiled for the baseline instruction set of the build (SSE2 on x86-64).
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
namespace baseline
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
} // namespace baseline

const SimdKernels&
baselineKernels()
{
  static const SimdKernels kernels{
    {&baseline::rows::moments, &baseline::rows::window_smoothing, &baseline::rows::window_row, &baseline::rows::window_scratch,
     &baseline::rows::window_row_spread},
    baseline::plane_fits::kPlaneFitKernels};
  return kernels;
}

} // namespace detail
} // namespace range_nlm
