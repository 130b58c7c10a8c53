// The baseline plane-fit kernels and the run-time choice between them and the AVX2 / AVX-512 ones.
#include "plane_fit.h"
#include "kernel_rows.h"

#include <cmath>
#include <cstring>
#include <limits>

namespace range_nlm
{
namespace detail
{
namespace baseline
{
#include "plane_fit.inc"
} // namespace baseline

const PlaneFitKernels&
avx2PlaneFitKernels();
const PlaneFitKernels&
avx512PlaneFitKernels();

const PlaneFitKernels&
baselinePlaneFitKernels()
{
  return baseline::kPlaneFitKernels;
}

const PlaneFitKernels&
planeFitKernels()
{
#if defined(__x86_64__) && defined(RANGE_NLM_HAVE_AVX512_KERNELS)
  if (cpuRunsAvx512())
    return avx512PlaneFitKernels();
#endif
#if defined(__x86_64__) && defined(RANGE_NLM_HAVE_AVX2_KERNELS)
  if (cpuRunsAvx2())
    return avx2PlaneFitKernels();
#endif
  return baseline::kPlaneFitKernels;
}

} // namespace detail
} // namespace range_nlm
