// The plane-fit kernels compiled for AVX-512 (F, VL, DQ, BW) with 512-bit vectors (this file
// only; chosen at run time when the CPU has them). No Eigen or PCL type crosses this file, so its
// alignment assumptions cannot leak.
#include "plane_fit.h"

#include <cmath>
#include <cstring>
#include <limits>

namespace range_nlm
{
namespace detail
{
namespace avx512
{
#include "plane_fit.inc"
} // namespace avx512

const PlaneFitKernels&
avx512PlaneFitKernels()
{
  return avx512::kPlaneFitKernels;
}
} // namespace detail
} // namespace range_nlm
