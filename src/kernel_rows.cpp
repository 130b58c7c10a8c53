// The baseline row kernels and the run-time choice between them and the AVX2 and AVX-512 ones.
#include "kernel_math.h"
#include "kernel_rows.h"

#include <cstdlib>

namespace range_nlm
{
namespace detail
{
namespace baseline
{
#include "kernel_rows.inc"
} // namespace baseline

const RowKernels&
avx2RowKernels();
const RowKernels&
avx512RowKernels();

const RowKernels&
baselineRowKernels()
{
  return baseline::kKernels;
}

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
  static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return avx2;
#else
  return false;
#endif
}

std::vector<const RowKernels*>
supportedRowKernels()
{
  std::vector<const RowKernels*> all{&baseline::kKernels};
#if defined(__x86_64__) && defined(RANGE_NLM_HAVE_AVX2_KERNELS)
  if (cpuRunsAvx2())
    all.push_back(&avx2RowKernels());
#endif
#if defined(__x86_64__) && defined(RANGE_NLM_HAVE_AVX512_KERNELS)
  if (cpuRunsAvx512())
    all.push_back(&avx512RowKernels());
#endif
  return all;
}

const RowKernels&
rowKernels()
{
#if defined(__x86_64__) && defined(RANGE_NLM_HAVE_AVX512_KERNELS)
  if (cpuRunsAvx512())
    return avx512RowKernels();
#endif
#if defined(__x86_64__) && defined(RANGE_NLM_HAVE_AVX2_KERNELS)
  if (cpuRunsAvx2())
    return avx2RowKernels();
#endif
  return baseline::kKernels;
}

} // namespace detail
} // namespace range_nlm
