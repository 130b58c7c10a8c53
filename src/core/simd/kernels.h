// The SIMD kernels of the filter (internal): the normal fits' moments and batched plane fits,
// the range pre-smoothing and the windowed offset evaluation. They work on raw pointers only, so
// the same sources (row_kernels.inc, window_kernel.inc, plane_fit_kernels.inc) are compiled once
// per instruction set (kernels_baseline.cpp, kernels_avx2.cpp, kernels_avx512.cpp) and one table
// (dispatch.cpp) chooses a build at run time; no inline function with external linkage is shared
// between the builds, and no Eigen or PCL type crosses them.
#pragma once

#include <cstddef>
#include <vector>

namespace range_nlm
{
namespace detail
{

/// One row of a padded SoA frame: pointers to x, y, z and the validity flag (1/0).
struct RowPointers
{
  const float* x;
  const float* y;
  const float* z;
  const float* f;
};

/// Pixels of a row evaluated together by the windowed evaluation (one per vector lane).
constexpr int kWindowLanes = 16;

/// A frame of the windowed evaluation: x, y, z planes padded so that every window read of every
/// row stays inside (NaN at invalid and outside pixels), pointing at pixel (0, 0); the frame
/// weight; 1 / d^2 and 1 / s^2 of the row's pixels (WindowTask::lane_width values) or, when null,
/// the scalars.
struct WindowPlane
{
  const float* x = nullptr;
  const float* y = nullptr;
  const float* z = nullptr;
  float psi = 1.0f;
  const float* inv_d2 = nullptr;
  const float* inv_s2 = nullptr;
  float d2 = 0.0f, s2 = 0.0f;
  /// The padded planes the centre patch a(o) is taken from when this frame's patches are compared
  /// (FrameTerm::patches; null: WindowTask::center).
  const float* patch_x = nullptr;
  const float* patch_y = nullptr;
  const float* patch_z = nullptr;
  /// The frame's own search window (FrameTerm::search_window), odd and at most WindowTask::search;
  /// 0: WindowTask::search.
  int search = 0;
};

/// Everything one row of the windowed evaluation reads. The per-pixel arrays hold the row's
/// pixels, lane_width values (the width rounded up to kWindowLanes); pixels past the width and
/// inactive pixels have active 0 and a zero normal.
struct WindowTask
{
  int lane_width = 0;
  int search = 0;
  int patch = 0;
  std::ptrdiff_t stride = 0; // row stride of the padded planes
  WindowPlane center;        // the filtered frame (its patches)
  const WindowPlane* frames = nullptr;
  int frame_count = 0;
  /// The one smaller search window the other frames may have (WindowPlane::search), 0 if none:
  /// their sums are scaled by the centre frame's weight over `search` relative to its weight over
  /// this inner window (see window_row_p).
  int inner_search = 0;
  /// The patch gate of the row's pixels (FilterParameters::patch_edge_gate): centre patch pixels
  /// with |a(o)| above it count as holes. Null: no gate.
  const float* gate = nullptr;
  const float* nx = nullptr;
  const float* ny = nullptr;
  const float* nz = nullptr;
  const float* active = nullptr;
};

struct RowKernels
{
  /// Moments of one neighbour offset for a row of centres (normal estimation): q = p_j - p_i,
  /// w = flag_j if |rho_j - rho_i| * range_on <= gate and |q . n0| <= gate, then
  /// acc[0..9] += w * (1, qx, qy, qz, qx qx, qx qy, qx qz, qy qy, qy qz, qz qz), each a row.
  void (*moments)(RowPointers c, const float* c_rho, RowPointers q, const float* q_rho, const float* gate,
                  const float* n0x, const float* n0y, const float* n0z, float range_on, int width, float* acc);
  /// The range pre-smoothing of a row of centres over a whole (2r+1) x (2r+1) window: for the
  /// offsets (dv, du) = (-r, -r) ... (r, r) in that order, d = rho_j - rho_i,
  /// w = flag_j exp(-d^2 inv[u]), num[u] += w d, den[u] += w, from num = den = 0 (overwritten).
  /// rho and flag point to the row's first centre in padded planes of row stride `stride`
  /// (border >= r on every side).
  void (*window_smoothing)(const float* rho, const float* flag, std::ptrdiff_t stride, int r, const float* inv,
                           int width, float* num, float* den);
  /// The windowed evaluation of row v: the filtered offsets h of its lane_width pixels (0 for
  /// inactive ones) into `out`; `scratch` holds window_scratch() floats, aligned to 64 bytes.
  void (*window_row)(const WindowTask& task, int v, float* scratch, float* out);
  /// Floats of per-thread scratch window_row needs for a search window and patch size.
  std::size_t (*window_scratch)(int search_window, int patch_size);
  /// window_row that also writes, per pixel, the weighted variance of the candidates' heights
  /// about h, sum w (h_j - h)^2 / sum w, into spread[0 .. lane_width) and one over the effective
  /// number of candidates, sum w^2 / (sum w)^2, into spread[lane_width .. 2 lane_width) (0 for
  /// inactive pixels); a build of its own, so that window_row does no work for them.
  void (*window_row_spread)(const WindowTask& task, int v, float* scratch, float* out, float* spread);
};

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
  /// counts); rho, n0x, n0y, n0z and range_on are then not read. A null n0x means no plane gate
  /// (as n0 = 0), range_on = 0 no range gate: the test that is off is skipped.
  void (*window_moments)(const float* x, const float* y, const float* z, const float* f, const float* rho,
                         std::ptrdiff_t stride, int r, const float* gate, const float* n0x, const float* n0y,
                         const float* n0z, float range_on, int width, float* acc);
};

/// One build of every kernel, for one instruction set.
struct SimdKernels
{
  RowKernels rows;
  PlaneFitKernels plane_fits;
};

/// Whether this CPU runs the AVX-512 (F, VL, DQ, BW) kernels; RANGE_NLM_NO_AVX512 in the
/// environment turns them off (for comparisons).
bool
cpuRunsAvx512();
/// Whether this CPU runs the AVX2 + FMA kernels; RANGE_NLM_NO_AVX2 in the environment turns them
/// off (with RANGE_NLM_NO_AVX512 too, the baseline build runs; for comparisons).
bool
cpuRunsAvx2();

/// For code outside the kernel files built for those instruction sets as well (function targets,
/// x86-64 only; chosen at run time with cpuRunsAvx2 / cpuRunsAvx512): [[RANGE_NLM_TARGET_AVX2]].
#define RANGE_NLM_TARGET_AVX2 gnu::target("avx2")
#define RANGE_NLM_TARGET_AVX512 gnu::target("avx512f,avx512vl,avx512dq,avx512bw,prefer-vector-width=512")

/// The fastest kernels this CPU supports.
const RowKernels&
rowKernels();
/// The baseline kernels (for tests).
const RowKernels&
baselineRowKernels();
/// Every build of the kernels this CPU runs: baseline, then AVX2, then AVX-512 (for tests).
std::vector<const RowKernels*>
supportedRowKernels();

/// The fastest plane-fit kernels this CPU supports.
const PlaneFitKernels&
planeFitKernels();
/// The baseline kernels (for tests).
const PlaneFitKernels&
baselinePlaneFitKernels();

/// The builds, each defined in its own translation unit (kernels_<isa>.cpp).
const SimdKernels&
baselineKernels();
const SimdKernels&
avx2Kernels();
const SimdKernels&
avx512Kernels();

} // namespace detail
} // namespace range_nlm
