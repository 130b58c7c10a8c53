// The one run-time choice among the builds of the SIMD kernels: AVX-512 where the CPU has it,
// else AVX2 + FMA, else the baseline build.
#include "kernels.h"

#include <cstdlib>

namespace range_nlm
{
namespace detail
{

bool
cpuRunsAvx512()
{
#if defined(__x86_64__)
  static const bool avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
                             __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw") &&
                             std::getenv("RANGE_NLM_NO_AVX512") == nullptr;
  return avx512;
#else
  return false;
#endif
}

bool
cpuRunsAvx2()
{
#if defined(__x86_64__)
  static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
                           std::getenv("RANGE_NLM_NO_AVX2") == nullptr;
  return avx2;
#else
  return false;
#endif
}

namespace
{

/// Every build this CPU runs, slowest first.
std::vector<const SimdKernels*>
supportedBuilds()
{
  std::vector<const SimdKernels*> all{&baselineKernels()};
#if defined(__x86_64__) && defined(RANGE_NLM_HAVE_AVX2_KERNELS)
  if (cpuRunsAvx2())
    all.push_back(&avx2Kernels());
#endif
#if defined(__x86_64__) && defined(RANGE_NLM_HAVE_AVX512_KERNELS)
  if (cpuRunsAvx512())
    all.push_back(&avx512Kernels());
#endif
  return all;
}

const SimdKernels&
fastestBuild()
{
  static const SimdKernels* const fastest = supportedBuilds().back();
  return *fastest;
}

} // namespace

const RowKernels&
rowKernels()
{
  return fastestBuild().rows;
}

const RowKernels&
baselineRowKernels()
{
  return baselineKernels().rows;
}

std::vector<const RowKernels*>
supportedRowKernels()
{
  std::vector<const RowKernels*> rows;
  for (const SimdKernels* build : supportedBuilds())
    rows.push_back(&build->rows);
  return rows;
}

const PlaneFitKernels&
planeFitKernels()
{
  return fastestBuild().plane_fits;
}

const PlaneFitKernels&
baselinePlaneFitKernels()
{
  return baselineKernels().plane_fits;
}

} // namespace detail
} // namespace range_nlm
