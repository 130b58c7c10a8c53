// Row kernels of the box-filtered evaluation (internal). They work on raw pointers only, so the
// same source (kernel_rows.inc) is compiled once for the baseline ISA and once for AVX2+FMA and
// chosen at run time; no inline function with external linkage is shared between the two.
#pragma once

#include <algorithm>
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

/// Fixed distance between the fields of one row in the box-filter buffers (ring rows, products,
/// staged per-pixel maps, weight sums), so that the hot loops address every field from one
/// pointer. A row of box sums holds at most this many pixels.
constexpr int kRowStride = 1040;
/// Fields of a ring row: the kChannels box-summed channels, then the unfiltered D (x, y, z) and
/// the pair flag of the row's own pixels.
constexpr int kRingFields = kChannels + 4;
/// Floats after a ring row's last field that box_row may write (its vector tail).
constexpr int kRingSlack = 64;
/// Fields of the staged per-pixel maps of a weight side: (nx, ny, nz) / s and 1 / d^2.
constexpr int kSideFields = 4;

/// The ring of horizontally box-summed rows whose sum is the vertical box sum: P rows (oldest
/// last), each kRingFields x kRowStride floats (plus kRingSlack), offset to the first pixel; the
/// middle one is the row whose weights are formed.
struct BoxRows
{
  const float* const* rows;
  int count;
};

/// The output pixels one side of a shift updates: their staged maps (kSideFields fields) and
/// weight sums (num / s, then den, kRowStride apart), offset to the first pixel.
struct WeightSide
{
  const float* maps;
  float* sums;
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
  /// Products D D^T (and the pair flag) for `n + patch - 1` pixels of centre row c and candidate
  /// row k, rounded up to 16 (both offset to the first pixel, with that much readable slack;
  /// prod holds kChannels x kRowStride floats), then their
  /// horizontal box sums over `patch` pixels into the first kChannels fields of the ring row
  /// `out`, and the unfiltered D and flag of the n middle pixels into its last 4 fields.
  void (*box_row)(RowPointers c, RowPointers k, int n, int patch, float* prod, float* out);
  /// For n pixels u of one shift delta: M = the vertical box sum of `box`, D and flag m from its
  /// middle row, Sim = n^T M n / pairs, and per side
  ///   w = psi m exp(-(|D|^2 / d^2 + Sim / s^2)), num += w h / s, den += w
  /// with h = n . D for side a (the pixels of the D row, candidates p + delta) and h = -n . D for
  /// side b (the candidate pixels, whose candidates p - delta give the same D D^T). a or b may
  /// be null.
  void (*shift_weights)(const BoxRows& box, int n, float psi, const WeightSide* a, const WeightSide* b);
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

} // namespace detail
} // namespace range_nlm
