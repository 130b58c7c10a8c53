// The row kernels compiled for AVX2 + FMA (this file only; chosen at run time when the CPU has
// them). No Eigen or PCL type crosses this file, so its alignment assumptions cannot leak.
#include "kernel_math.h"
#include "kernel_rows.h"

namespace range_nlm
{
namespace detail
{
namespace avx2
{
#include "kernel_rows.inc"
} // namespace avx2

const RowKernels&
avx2RowKernels()
{
  return avx2::kKernels;
}
} // namespace detail
} // namespace range_nlm
