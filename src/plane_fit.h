// Batched least-squares plane fits (internal): the eigenvector of the smallest eigenvalue of many
// symmetric 3x3 matrices at once, branch-free so that the loops vectorize. Only raw pointers
// cross these files, so the same source (plane_fit.inc) is compiled once for the baseline ISA
// and once for AVX2+FMA and chosen at run time, like the row kernels (kernel_rows.h).
#pragma once

#include <cstddef>

namespace range_nlm
{
namespace detail
{

struct PlaneFitKernels
{
  /// For n symmetric 3x3 matrices given as six SoA rows of n doubles (entries 00, 01, 02, 11,
  /// 12, 22: cov[k * n + i]), the unit eigenvector of the smallest eigenvalue into
  /// out[0 * n + i], out[1 * n + i], out[2 * n + i] and the smallest eigenvalue (the Rayleigh
  /// quotient of that vector) into out[3 * n + i].
  /// The sign of the vector is arbitrary (but deterministic). All four are NaN when the trace is
  /// not positive and finite, when the matrix has (numerically) rank <= 1 (collinear points: no
  /// plane), or when no eigenvector can be formed.
  void (*smallest_eigenvectors)(const double* cov, std::size_t n, double* out);
  /// Normals of one row of neighbourhoods from their moments (normal estimation):
  /// acc[k * width + u] for k = 0..9 holds (count, sx, sy, sz, sxx, sxy, sxz, syy, syz, szz) of
  /// the neighbours relative to the centre point p = (px, py, pz)[u], flag[u] its validity (1/0).
  /// The covariance (in double) is solved as above; the unit normal, turned toward the viewpoint
  /// view[0..2], goes to nx, ny, nz as float. NaN where the point is invalid, where count < 2.5,
  /// or where the solver gives no vector.
  void (*normals)(const float* acc, const float* px, const float* py, const float* pz, const float* flag,
                  const float* view, int width, float* nx, float* ny, float* nz);
  /// Gated moments of a whole (2r+1) x (2r+1) window for a row of centres: the sums that
  /// RowKernels::moments accumulates over the offsets (dv, du) = (-r, -r) ... (r, r), in that
  /// order, into acc[k * width + u] (overwritten), but with the ten sums of a block of centres
  /// kept in registers over all offsets. x, y, z, f, rho point to the row's first centre in a
  /// padded SoA grid of row stride `stride` (border >= r on every side); gate, n0x, n0y, n0z and
  /// range_on as for RowKernels::moments. A null gate means no gate (every valid neighbour
  /// counts); rho, n0x, n0y, n0z and range_on are then not read.
  void (*window_moments)(const float* x, const float* y, const float* z, const float* f, const float* rho,
                         std::ptrdiff_t stride, int r, const float* gate, const float* n0x, const float* n0y,
                         const float* n0z, float range_on, int width, float* acc);
};

/// The fastest plane-fit kernels this CPU supports.
const PlaneFitKernels&
planeFitKernels();
/// The baseline kernels (for tests).
const PlaneFitKernels&
baselinePlaneFitKernels();

} // namespace detail
} // namespace range_nlm
