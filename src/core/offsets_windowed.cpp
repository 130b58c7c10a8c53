// The windowed evaluation (kernel_window.inc): frames copied into NaN-padded planes, per-pixel
// inputs laid out in rows of whole vectors, then one row kernel call per image row. Rows are
// independent, so the output does not depend on the number of threads.
#include "simd/kernels.h"

#include "internal.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

namespace range_nlm
{
namespace detail
{
namespace
{

int
laneWidth(int width)
{
  return (width + kWindowLanes - 1) / kWindowLanes * kWindowLanes;
}

/// The points of a row, NaN where invalid. Written as additions of -0 (x + -0 = x for every x,
/// including -0) or NaN, which GCC vectorizes; it does not if-convert three selects here.
void
copyValid(const float* __restrict gx, const float* __restrict gy, const float* __restrict gz,
          const unsigned char* __restrict valid, int width, float* __restrict x, float* __restrict y,
          float* __restrict z)
{
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int u = 0; u < width; ++u) {
    const float keep = valid[u] > 0 ? -0.0f : nan;
    x[u] = gx[u] + keep;
    y[u] = gy[u] + keep;
    z[u] = gz[u] + keep;
  }
}

/// x, y, z of a frame with `pad` NaN pixels above, below and left of it and enough on the right
/// for the vectors and windows of the last lanes. Written once, in parallel rows.
struct NanPaddedFrame
{
  int pad = 0;
  std::ptrdiff_t stride = 0;
  float *x, *y, *z;

  /// Floats of one plane: one row more than the padded frame, since the last vectors of the
  /// last row may read past its end.
  static std::size_t planeSize(const Grid& g, int pad, std::ptrdiff_t stride)
  {
    return static_cast<std::size_t>(stride) * (g.height + 2 * pad + 1);
  }

  /// Writes the three planes at `base` (3 planeSize() floats).
  NanPaddedFrame(const Grid& g, int pad_, std::ptrdiff_t stride_, int threads, float* base)
    : pad(pad_), stride(stride_)
  {
    const int rows = g.height + 2 * pad;
    const std::size_t n = planeSize(g, pad, stride);
    x = base;
    y = base + n;
    z = base + 2 * n;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    (void)threads;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int row = 0; row < rows + 1; ++row) {
      float* px = &x[static_cast<std::size_t>(row) * stride];
      float* py = &y[static_cast<std::size_t>(row) * stride];
      float* pz = &z[static_cast<std::size_t>(row) * stride];
      const int v = row - pad;
      const bool inside = v >= 0 && v < g.height;
      // NaN in [0, left) and [right, stride); each element is written once.
      const int left = inside ? pad : static_cast<int>(stride);
      const int right = inside ? pad + g.width : static_cast<int>(stride);
      std::fill(px, px + left, nan), std::fill(py, py + left, nan), std::fill(pz, pz + left, nan);
      std::fill(px + right, px + stride, nan), std::fill(py + right, py + stride, nan);
      std::fill(pz + right, pz + stride, nan);
      if (inside) {
        const std::size_t i0 = static_cast<std::size_t>(v) * g.width;
        copyValid(&g.x[i0], &g.y[i0], &g.z[i0], &g.valid[i0], g.width, px + pad, py + pad, pz + pad);
      }
    }
  }
  std::size_t origin() const { return static_cast<std::size_t>(pad) * stride + pad; }
  WindowPlane plane() const
  {
    WindowPlane w;
    w.x = &x[origin()];
    w.y = &y[origin()];
    w.z = &z[origin()];
    return w;
  }
};

/// The staged row of the windowed evaluation: the normal and active = 1 of points that are
/// valid, selected and have a finite normal, else zeros. Every load is unconditional, so the
/// loop vectorizes.
void
stageRow(const float* __restrict gx, const float* __restrict gy, const float* __restrict gz,
         const unsigned char* __restrict valid, const unsigned char* __restrict selected, int width,
         float* __restrict sx, float* __restrict sy, float* __restrict sz, float* __restrict sa)
{
  for (int u = 0; u < width; ++u) {
    // A NaN normal fails the comparisons (so does an infinite one).
    const float nx = gx[u], ny = gy[u], nz = gz[u];
    const float on = valid[u], chosen = selected[u];
    const bool ok = (on > 0.0f) & (chosen > 0.0f) & (std::fabs(nx) <= 1e30f) & (std::fabs(ny) <= 1e30f) &
                    (std::fabs(nz) <= 1e30f);
    sx[u] = ok ? nx : 0.0f;
    sy[u] = ok ? ny : 0.0f;
    sz[u] = ok ? nz : 0.0f;
    sa[u] = ok ? 1.0f : 0.0f;
  }
}

} // namespace

void
computeOffsetsWindowed(const RowKernels& kernels, const Grid& center, const NormalField& normals,
                       const std::vector<FrameTerm>& frames, int search_window, int patch_size, int threads,
                       const std::vector<unsigned char>& active, std::vector<float>& offsets,
                       const std::vector<float>& patch_gate, std::vector<float>* storage, OffsetSpread* spread)
{
  const int width = center.width;
  const int height = center.height;
  const int lane_width = laneWidth(width);
  if (spread) {
    spread->variance.resize(center.size());
    spread->inverse_count.resize(center.size());
  }
  const int reach = search_window / 2 + patch_size / 2;
  // Reads of a row reach from `reach` columns before its first pixel to the window of its last
  // vector: lane_width, then the search window plus the patch; 8 more keep every read inside.
  const std::ptrdiff_t stride = reach + lane_width + search_window + patch_size + 8;

  // The centre frame, then every other frame and patch guide, 3 planes each, in one buffer.
  const std::size_t plane_size = NanPaddedFrame::planeSize(center, reach, stride);
  std::vector<const Grid*> grids{&center};
  for (const FrameTerm& term : frames)
    for (const Grid* grid : {term.grid, term.patches})
      if (grid && std::find(grids.begin(), grids.end(), grid) == grids.end())
        grids.push_back(grid);
  const std::size_t padded_count = grids.size();
  std::unique_ptr<float[]> own;
  float* next = nullptr;
  if (storage) {
    storage->resize(3 * plane_size * padded_count);
    next = storage->data();
  } else {
    own.reset(new float[3 * plane_size * padded_count]);
    next = own.get();
  }
  const NanPaddedFrame padded_center(center, reach, stride, threads, next);
  // Each grid is padded once, however many terms name it.
  std::vector<std::pair<const Grid*, std::unique_ptr<NanPaddedFrame>>> padded;
  const auto paddedPlane = [&](const Grid* grid) {
    if (grid == &center)
      return padded_center.plane();
    for (const auto& known : padded)
      if (known.first == grid)
        return known.second->plane();
    next += 3 * plane_size;
    padded.emplace_back(grid, std::make_unique<NanPaddedFrame>(*grid, reach, stride, threads, next));
    return padded.back().second->plane();
  };
  std::vector<WindowPlane> planes(frames.size());
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const FrameTerm& term = frames[f];
    WindowPlane& w = planes[f];
    w = paddedPlane(term.grid);
    if (term.patches && term.patches != &center) {
      const WindowPlane guide = paddedPlane(term.patches);
      w.patch_x = guide.x;
      w.patch_y = guide.y;
      w.patch_z = guide.z;
    }
    w.psi = term.weight;
    w.search = term.search_window;
    w.d2 = inverseSquare(term.distance_bandwidth);
    w.s2 = inverseSquare(term.similarity_bandwidth);
  }
  const std::size_t scratch_floats = kernels.window_scratch(search_window, patch_size);
  const std::size_t frame_count = frames.size();
#pragma omp parallel num_threads(threads)
  {
    // Per thread: the kernel scratch (cache-line aligned), then the staged row: normal, active
    // flag, 1 / d^2 and 1 / s^2 per frame, the patch gate, and the output (with `spread` also
    // its two rows).
    const std::size_t row_floats = static_cast<std::size_t>(lane_width) * (6 + 2 * frame_count + (spread ? 2 : 0));
    std::vector<float> storage(scratch_floats + row_floats + 16);
    const std::uintptr_t address = reinterpret_cast<std::uintptr_t>(storage.data());
    float* scratch = storage.data() + ((64 - address % 64) % 64) / sizeof(float);
    float* staged = scratch + scratch_floats;
    const auto field = [&](std::size_t k) { return staged + k * lane_width; };
    float* out = field(4);
    std::vector<WindowPlane> row_planes = planes;
    WindowTask task;
    task.lane_width = lane_width;
    task.search = search_window;
    task.patch = patch_size;
    task.stride = stride;
    task.center = padded_center.plane();
    task.frames = row_planes.data();
    task.frame_count = static_cast<int>(frame_count);
    const int inner = innerSearch(frames, search_window);
    task.inner_search = inner < search_window ? inner : 0;
    task.nx = field(0);
    task.ny = field(1);
    task.nz = field(2);
    task.active = field(3);
    float* const gate = field(5 + 2 * frame_count);
    if (!patch_gate.empty())
      task.gate = gate;
    for (std::size_t f = 0; f < frame_count; ++f) {
      if (frames[f].inverse_distance2)
        row_planes[f].inv_d2 = field(5 + 2 * f);
      if (frames[f].inverse_similarity2)
        row_planes[f].inv_s2 = field(6 + 2 * f);
    }
#pragma omp for schedule(dynamic, 1)
    for (int v = 0; v < height; ++v) {
      // Stage the row (inactive points: zero normal; past the width: zeros).
      const std::size_t first = static_cast<std::size_t>(v) * width;
      // (Without a selection every valid point is selected.)
      const unsigned char* valid = &center.valid[first];
      stageRow(&normals.nx[first], &normals.ny[first], &normals.nz[first], valid,
               active.empty() ? valid : &active[first], width, field(0), field(1), field(2), field(3));
      for (int k = 0; k < 4; ++k)
        std::fill(field(k) + width, field(k) + lane_width, 0.0f);
      if (task.gate) {
        std::copy_n(&patch_gate[first], width, gate);
        std::fill(gate + width, gate + lane_width, 0.0f);
      }
      for (std::size_t f = 0; f < frame_count; ++f) {
        if (frames[f].inverse_distance2)
          std::copy_n(&(*frames[f].inverse_distance2)[first], width, field(5 + 2 * f));
        if (frames[f].inverse_similarity2)
          std::copy_n(&(*frames[f].inverse_similarity2)[first], width, field(6 + 2 * f));
      }
      const std::ptrdiff_t at = static_cast<std::ptrdiff_t>(first);
      if (spread) {
        // Its own build may contract the sums into other multiply-adds: the offsets come from the
        // default build below, so that they are the same bits with the option on or off.
        float* const sums = field(6 + 2 * frame_count);
        kernels.window_row_spread(task, v, scratch, out, sums);
        std::copy(sums, sums + width, spread->variance.begin() + at);
        std::copy(sums + lane_width, sums + lane_width + width, spread->inverse_count.begin() + at);
      }
      kernels.window_row(task, v, scratch, out);
      std::copy(out, out + width, offsets.begin() + at);
    }
  }
}

void
computeOffsetsFast(const Grid& center, const NormalField& normals, const std::vector<FrameTerm>& frames,
                   int search_window, int patch_size, int threads, const std::vector<unsigned char>& active,
                   std::vector<float>& offsets, const std::vector<float>& patch_gate, std::vector<float>* planes,
                   OffsetSpread* spread)
{
  computeOffsetsWindowed(rowKernels(), center, normals, frames, search_window, patch_size, threads, active, offsets,
                         patch_gate, planes, spread);
}

} // namespace detail
} // namespace range_nlm
