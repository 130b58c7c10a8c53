// Row kernels of the windowed evaluation, the normal fits' moments and the range pre-smoothing
// (internal). They work on raw pointers only, so the same source (kernel_rows.inc) is compiled
// for the baseline instruction set, for AVX2 + FMA and for AVX-512 and chosen at run time; no
// inline function with external linkage is shared between the builds.
#pragma once

#include <range_nlm/kernel.h>

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
  /// One neighbour offset of the range pre-smoothing: d = rho_j - rho_i,
  /// w = flag_j exp(-d^2 inv[u]); num += w d; den += w.
  void (*smoothing)(const float* c_rho, const float* q_rho, const float* q_flag, const float* inv, int width,
                    float* num, float* den);
  /// The windowed evaluation of row v: the filtered offsets h of its lane_width pixels (0 for
  /// inactive ones) into `out`; `scratch` holds window_scratch() floats, aligned to 64 bytes.
  void (*window_row)(const WindowTask& task, int v, float* scratch, float* out);
  /// Floats of per-thread scratch window_row needs for a search window and patch size.
  std::size_t (*window_scratch)(int search_window, int patch_size);
};

/// The windowed evaluation (computeOffsets' fast path) with the given build of the row kernels;
/// `offsets` has the size of the grid. The padded frames go into `planes` if given (resized as
/// needed), else into memory of their own. For tests; computeOffsets takes rowKernels().
void
computeOffsetsWindowed(const RowKernels& kernels, const Grid& center, const NormalField& normals,
                       const std::vector<FrameTerm>& frames, int search_window, int patch_size, int threads,
                       const std::vector<unsigned char>& active, std::vector<float>& offsets,
                       std::vector<float>* planes = nullptr);

/// Whether this CPU runs the AVX-512 (F, VL, DQ, BW) kernels; RANGE_NLM_NO_AVX512 in the
/// environment turns them off (for comparisons).
bool
cpuRunsAvx512();
/// Whether this CPU runs the AVX2 + FMA kernels.
bool
cpuRunsAvx2();

/// The fastest kernels this CPU supports.
const RowKernels&
rowKernels();
/// The baseline kernels (for tests).
const RowKernels&
baselineRowKernels();
/// Every build of the kernels this CPU runs: baseline, then AVX2, then AVX-512 (for tests).
std::vector<const RowKernels*>
supportedRowKernels();

} // namespace detail
} // namespace range_nlm
