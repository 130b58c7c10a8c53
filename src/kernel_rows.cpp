// The baseline row kernels and the run-time choice between them and the AVX2 ones.
#include "kernel_math.h"
#include "kernel_rows.h"

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
baselineRowKernels()
{
  return baseline::kKernels;
}

const RowKernels&
rowKernels()
{
#if defined(__x86_64__) && defined(RANGE_NLM_HAVE_AVX2_KERNELS)
  static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  if (avx2)
    return avx2RowKernels();
#endif
  return baseline::kKernels;
}

} // namespace detail
} // namespace range_nlm
