// The windowed evaluation (kernel_window.inc): frames copied into NaN-padded planes, per-pixel
// inputs laid out in rows of whole vectors, then one row kernel call per image row. Rows are
// independent, so the output does not depend on the number of threads.
#include "kernel_rows.h"

#include <range_nlm/kernel.h>

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

/// x, y, z of a frame with `pad` NaN pixels above, below and left of it and enough on the right
/// for the vectors and windows of the last lanes.
struct NanPaddedFrame
{
  int pad = 0;
  std::ptrdiff_t stride = 0;
  std::vector<float> x, y, z;

  NanPaddedFrame(const Grid& g, int pad_, std::ptrdiff_t stride_, int threads) : pad(pad_), stride(stride_)
  {
    const std::size_t n = static_cast<std::size_t>(stride) * (g.height + 2 * pad) + 2 * kWindowLanes;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    x.assign(n, nan);
    y.assign(n, nan);
    z.assign(n, nan);
    (void)threads;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int v = 0; v < g.height; ++v)
      for (int u = 0; u < g.width; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * g.width + u;
        if (!g.valid[i])
          continue;
        const std::size_t k = origin() + static_cast<std::size_t>(v) * stride + u;
        x[k] = g.x[i];
        y[k] = g.y[i];
        z[k] = g.z[i];
      }
  }
  std::size_t origin() const { return static_cast<std::size_t>(pad) * stride + pad; }
};

/// A per-pixel map (width x height) in rows of lane_width values, zero past the width.
std::vector<float>
laneRows(const std::vector<float>& map, int width, int height, int lane_width, int threads)
{
  std::vector<float> out(static_cast<std::size_t>(lane_width) * height, 0.0f);
  (void)threads;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u)
      out[static_cast<std::size_t>(v) * lane_width + u] = map[static_cast<std::size_t>(v) * width + u];
  return out;
}

} // namespace

void
computeOffsetsWindowed(const Grid& center, const NormalField& normals, const std::vector<FrameTerm>& frames,
                       int search_window, int patch_size, int threads, const std::vector<unsigned char>& active,
                       std::vector<float>& offsets)
{
  const RowKernels& kernels = rowKernels();
  const int width = center.width;
  const int height = center.height;
  const int lane_width = laneWidth(width);
  const int reach = search_window / 2 + patch_size / 2;
  // A window row of the last vector ends window_scratch's columns past its first pixel at most:
  // search rounded up to 4 shifts, plus the patch; 8 more keep every read inside.
  const std::ptrdiff_t stride = reach + lane_width + search_window + patch_size + 8;

  const NanPaddedFrame padded_center(center, reach, stride, threads);
  std::vector<std::unique_ptr<NanPaddedFrame>> padded(frames.size());
  std::vector<std::vector<float>> maps_d2(frames.size()), maps_s2(frames.size());
  std::vector<WindowPlane> planes(frames.size());
  const auto plane = [](const NanPaddedFrame& p) {
    WindowPlane w;
    w.x = &p.x[p.origin()];
    w.y = &p.y[p.origin()];
    w.z = &p.z[p.origin()];
    return w;
  };
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const FrameTerm& term = frames[f];
    const NanPaddedFrame* p = &padded_center;
    if (term.grid != &center) {
      padded[f] = std::make_unique<NanPaddedFrame>(*term.grid, reach, stride, threads);
      p = padded[f].get();
    }
    WindowPlane& w = planes[f];
    w = plane(*p);
    w.psi = term.weight;
    w.d2 = inverseSquare(term.distance_bandwidth);
    w.s2 = inverseSquare(term.similarity_bandwidth);
    if (term.inverse_distance2) {
      maps_d2[f] = laneRows(*term.inverse_distance2, width, height, lane_width, threads);
      w.inv_d2 = maps_d2[f].data();
    }
    if (term.inverse_similarity2) {
      maps_s2[f] = laneRows(*term.inverse_similarity2, width, height, lane_width, threads);
      w.inv_s2 = maps_s2[f].data();
    }
  }

  // Normals and the active flag in lane rows; inactive points get a zero normal.
  const std::size_t lanes = static_cast<std::size_t>(lane_width) * height;
  std::vector<float> nx(lanes, 0.0f), ny(lanes, 0.0f), nz(lanes, 0.0f), act(lanes, 0.0f);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * width + u;
      const std::size_t k = static_cast<std::size_t>(v) * lane_width + u;
      const bool ok = center.valid[i] && (active.empty() || active[i]) && std::isfinite(normals.nx[i]) &&
                      std::isfinite(normals.ny[i]) && std::isfinite(normals.nz[i]);
      if (!ok)
        continue;
      nx[k] = normals.nx[i];
      ny[k] = normals.ny[i];
      nz[k] = normals.nz[i];
      act[k] = 1.0f;
    }

  WindowTask task;
  task.lane_width = lane_width;
  task.search = search_window;
  task.patch = patch_size;
  task.stride = stride;
  task.center = plane(padded_center);
  task.frames = planes.data();
  task.frame_count = static_cast<int>(planes.size());
  task.nx = nx.data();
  task.ny = ny.data();
  task.nz = nz.data();
  task.active = act.data();
  const std::size_t scratch_floats = kernels.window_scratch(search_window, patch_size);
#pragma omp parallel num_threads(threads)
  {
    // Scratch aligned to a cache line, and one output row.
    std::vector<float> storage(scratch_floats + lane_width + 16);
    const std::uintptr_t address = reinterpret_cast<std::uintptr_t>(storage.data());
    float* scratch = storage.data() + ((64 - address % 64) % 64) / sizeof(float);
    float* out = scratch + scratch_floats;
#pragma omp for schedule(dynamic, 1)
    for (int v = 0; v < height; ++v) {
      kernels.window_row(task, v, scratch, out);
      std::copy(out, out + width, offsets.begin() + static_cast<std::ptrdiff_t>(v) * width);
    }
  }
}

} // namespace detail
} // namespace range_nlm
