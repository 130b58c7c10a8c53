// The baseline plane-fit kernels and the run-time choice between them and the AVX2 / AVX-512 ones.
#include "plane_fit.h"

#include <cmath>
#include <cstdlib>
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
  static const bool avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
                             __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw") &&
                             std::getenv("RANGE_NLM_NO_AVX512") == nullptr;
  if (avx512)
    return avx512PlaneFitKernels();
#endif
#if defined(__x86_64__) && defined(RANGE_NLM_HAVE_AVX2_KERNELS)
  static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  if (avx2)
    return avx2PlaneFitKernels();
#endif
  return baseline::kPlaneFitKernels;
}

} // namespace detail
} // namespace range_nlm
