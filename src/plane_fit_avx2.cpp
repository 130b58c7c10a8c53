// The plane-fit kernels compiled for AVX2 + FMA (this file only; chosen at run time when the CPU
// has them). No Eigen or PCL type crosses this file, so its alignment assumptions cannot leak.
#include "plane_fit.h"

#include <cmath>
#include <cstring>
#include <limits>

namespace range_nlm
{
namespace detail
{
namespace avx2
{
#include "plane_fit.inc"
} // namespace avx2

const PlaneFitKernels&
avx2PlaneFitKernels()
{
  return avx2::kPlaneFitKernels;
}
} // namespace detail
} // namespace range_nlm
