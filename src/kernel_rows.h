// Row kernels of the box-filtered evaluation (internal). They work on raw pointers only, so the
// same source (kernel_rows.inc) is compiled once for the baseline ISA and once for AVX2+FMA and
// chosen at run time; no inline function with external linkage is shared between the two.
#pragma once

#include <cstddef>

namespace range_nlm
{
namespace detail
{

/// Channels box-filtered per shift: D D^T entries xx, xy, xz, yy, yz, zz and the pair count.
constexpr int kChannels = 7;

/// One row of a padded SoA frame: pointers to x, y, z and the validity flag (1/0).
struct RowPointers
{
  const float* x;
  const float* y;
  const float* z;
  const float* f;
};

struct RowKernels
{
  /// Products D D^T (and the pair flag) for `width + patch - 1` pixels of centre row c and
  /// candidate row k (both already offset to the first pixel), then their horizontal box sums
  /// over `patch` pixels into out[ch * width + u].
  void (*products)(RowPointers c, RowPointers k, int width, int patch, float* prod, float* out);
  /// acc += add - sub (sub may be null), then copy = float(acc) if copy is not null.
  void (*slide)(double* acc, const float* add, const float* sub, float* copy, std::size_t n);
  /// Weights of one output row for one shift, accumulated into num / den:
  /// w = psi * exp(-(|p_i - p_j|^2 inv_d2[u] + Sim inv_s2[u])), Sim = n^T M n / pairs.
  void (*weights)(RowPointers c, RowPointers k, const float* active, const float* nx, const float* ny,
                  const float* nz, const float* m, int width, const float* inv_d2, const float* inv_s2,
                  float psi, float* num, float* den);
  /// out[q] = sum of rows[0..count-1][q] (fresh float sums: no running-sum drift).
  void (*column_sum)(const float* const* rows, int count, std::size_t n, float* out);
  /// Moments of one neighbour offset for a row of centres (normal estimation): q = p_j - p_i,
  /// w = flag_j if |rho_j - rho_i| * range_on <= gate and |q . n0| <= gate, then
  /// acc[0..9] += w * (1, qx, qy, qz, qx qx, qx qy, qx qz, qy qy, qy qz, qz qz), each a row.
  void (*moments)(RowPointers c, const float* c_rho, RowPointers q, const float* q_rho, const float* gate,
                  const float* n0x, const float* n0y, const float* n0z, float range_on, int width, float* acc);
  /// One neighbour offset of the range pre-smoothing: d = rho_j - rho_i,
  /// w = flag_j exp(-d^2 inv[u]); num += w d; den += w.
  void (*smoothing)(const float* c_rho, const float* q_rho, const float* q_flag, const float* inv, int width,
                    float* num, float* den);
};

/// The fastest kernels this CPU supports.
const RowKernels&
rowKernels();
/// The baseline kernels (for tests).
const RowKernels&
baselineRowKernels();

} // namespace detail
} // namespace range_nlm
