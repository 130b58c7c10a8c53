// Normal estimation over grid neighbourhoods and the edge-preserving pre-smoothing used for it.
#include "fast_math.h"
#include "simd/kernels.h"

#include "internal.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>

namespace range_nlm
{

NormalField
estimateNormals(const Grid& grid, int window, const Viewpoint& viewpoint, int threads)
{
  return estimateNormals(grid, window, viewpoint, threads, {});
}

NormalField
estimateNormals(const Grid& grid, int window, const Viewpoint& viewpoint, int threads,
                const std::vector<float>& gate)
{
  return detail::estimateNormalsGated(grid, window, viewpoint, threads, gate, gate.empty() ? 0 : 2);
}

namespace detail
{
namespace
{
/// The bits of a float, read and written through a type that may alias it.
typedef std::uint32_t Bits __attribute__((may_alias));

/// A grid copied into a padded SoA layout (border r, invalid points flag 0 and coordinates 0)
/// with the range of every point, so neighbourhood loops run over contiguous rows without
/// bounds checks and vectorize. Filled by `threads` threads, one padded row at a time (every
/// element written exactly once, so the buffers need no prior initialisation).
struct PaddedGrid
{
  int border, stride;
  std::unique_ptr<float[]> own;
  float *x, *y, *z, *f;
  float* rho = nullptr; // only with `ranges`
  /// The planes live in `storage` if given (resized as needed, so that repeated calls reuse
  /// it), else in memory of their own. The ranges are computed only with `ranges`.
  PaddedGrid(const Grid& g, int r, const Viewpoint& viewpoint, int threads, bool ranges,
             std::vector<float>* storage = nullptr)
      : border(r), stride(g.width + 2 * r)
  {
    const int rows = g.height + 2 * r;
    const std::size_t n = static_cast<std::size_t>(stride) * rows;
    const std::size_t planes = ranges ? 5 : 4;
    float* base = nullptr;
    if (storage) {
      storage->resize(planes * n);
      base = storage->data();
    } else {
      own.reset(new float[planes * n]);
      base = own.get();
    }
    x = base, y = base + n, z = base + 2 * n, f = base + 3 * n;
    if (ranges)
      rho = base + 4 * n;
    (void)threads;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int pv = 0; pv < rows; ++pv)
      fillRow(g, pv, viewpoint);
  }
  std::size_t at(int u, int v) const { return static_cast<std::size_t>(v + border) * stride + (u + border); }

private:
  /// Padded row pv: border columns 0, the interior copied (invalid points hold NaN, replaced by
  /// 0) and flagged, and the ranges if kept.
  void fillRow(const Grid& g, int pv, const Viewpoint& viewpoint)
  {
    const int r = border;
    float* __restrict px = &x[static_cast<std::size_t>(pv) * stride];
    float* __restrict py = &y[static_cast<std::size_t>(pv) * stride];
    float* __restrict pz = &z[static_cast<std::size_t>(pv) * stride];
    float* __restrict pf = &f[static_cast<std::size_t>(pv) * stride];
    const int v = pv - r;
    const bool inside = v >= 0 && v < g.height;
    // Border rows and columns are 0.
    const int width = g.width;
    const int left = inside ? r : stride; // zero [0, left) and [right, stride)
    const int right = inside ? r + width : stride;
    for (int pu = 0; pu < left; ++pu)
      px[pu] = 0.0f, py[pu] = 0.0f, pz[pu] = 0.0f, pf[pu] = 0.0f;
    for (int pu = right; pu < stride; ++pu)
      px[pu] = 0.0f, py[pu] = 0.0f, pz[pu] = 0.0f, pf[pu] = 0.0f;
    if (inside) {
      // Branch-free with bit masks: the compiler turns a select on `valid` into a branch per
      // point.
      const std::size_t i0 = static_cast<std::size_t>(v) * g.width;
      const Bits* __restrict gx = reinterpret_cast<const Bits*>(&g.x[i0]);
      const Bits* __restrict gy = reinterpret_cast<const Bits*>(&g.y[i0]);
      const Bits* __restrict gz = reinterpret_cast<const Bits*>(&g.z[i0]);
      const unsigned char* __restrict gv = &g.valid[i0];
      Bits* __restrict bx = reinterpret_cast<Bits*>(px + r);
      Bits* __restrict by = reinterpret_cast<Bits*>(py + r);
      Bits* __restrict bz = reinterpret_cast<Bits*>(pz + r);
      Bits* __restrict bf = reinterpret_cast<Bits*>(pf + r);
#pragma omp simd
      for (int u = 0; u < width; ++u) {
        const std::uint32_t keep = 0u - static_cast<std::uint32_t>(gv[u] != 0);
        bx[u] = gx[u] & keep, by[u] = gy[u] & keep, bz[u] = gz[u] & keep;
        bf[u] = 0x3f800000u & keep; // 1.0f
      }
    }
    if (!rho)
      return;
    float* __restrict pr = &rho[static_cast<std::size_t>(pv) * stride];
    const float vx = viewpoint[0], vy = viewpoint[1], vz = viewpoint[2];
#pragma omp simd
    for (int pu = 0; pu < stride; ++pu) {
      const float dx = px[pu] - vx, dy = py[pu] - vy, dz = pz[pu] - vz;
      pr[pu] = pf[pu] > 0.0f ? std::sqrt(dx * dx + dy * dy + dz * dz) : 0.0f;
    }
  }
};

/// One row's gates for the gated fits: g = gate where valid, else 1e30. Branch-free with bit
/// masks, so that it vectorizes.
inline void
rowGate(const float* gate, const unsigned char* __restrict valid, int width, float* g)
{
  const Bits* __restrict gv = reinterpret_cast<const Bits*>(gate);
  Bits* __restrict gb = reinterpret_cast<Bits*>(g);
  const Bits far = 0x7149f2cau; // 1e30f
#pragma omp simd
  for (int u = 0; u < width; ++u) {
    const std::uint32_t keep = 0u - static_cast<std::uint32_t>(valid[u] != 0);
    gb[u] = (gv[u] & keep) | (far & ~keep);
  }
}

/// One row of pass 1's normals for the plane gate of pass 2: n0 = the normal where finite, else
/// 0. Branch-free with bit masks, so that it vectorizes.
inline void
rowFirstNormals(const NormalField& first, std::size_t row, int width, float* n0x, float* n0y, float* n0z)
{
  const Bits* __restrict fx = reinterpret_cast<const Bits*>(&first.nx[row]);
  const Bits* __restrict fy = reinterpret_cast<const Bits*>(&first.ny[row]);
  const Bits* __restrict fz = reinterpret_cast<const Bits*>(&first.nz[row]);
  Bits* __restrict bx = reinterpret_cast<Bits*>(n0x);
  Bits* __restrict by = reinterpret_cast<Bits*>(n0y);
  Bits* __restrict bz = reinterpret_cast<Bits*>(n0z);
#pragma omp simd
  for (int u = 0; u < width; ++u) {
    const std::uint32_t finite = 0u - static_cast<std::uint32_t>((fx[u] & 0x7f800000u) != 0x7f800000u);
    bx[u] = fx[u] & finite, by[u] = fy[u] & finite, bz[u] = fz[u] & finite;
  }
}

/// One pass of estimateNormalsGated over an already padded grid; `first` is pass 1's result
/// (pass 2 only).
void
fitNormals(const Grid& grid, const PaddedGrid& pad, int window, const Viewpoint& viewpoint, int threads,
           const std::vector<float>& gate, int pass, const NormalField* first, NormalField& normals)
{
  const bool range_gated = pass == 1;
  const bool plane_gated = pass == 2;
  const int width = grid.width, height = grid.height;
  const int r = window / 2;
  const PlaneFitKernels& fits = planeFitKernels();
  const float view[3] = {viewpoint[0], viewpoint[1], viewpoint[2]};
  // Every element is written below (the plane fit covers whole rows).
  normals.nx.resize(grid.size());
  normals.ny.resize(grid.size());
  normals.nz.resize(grid.size());
  (void)threads;
#pragma omp parallel num_threads(threads)
  {
    // Per row: moments of the neighbourhood relative to p_i (a local origin keeps the float
    // sums well conditioned).
    std::vector<float> acc(10 * static_cast<std::size_t>(width));
    std::vector<float> g(width, 1e30f), n0x(width, 0.0f), n0y(width, 0.0f), n0z(width, 0.0f);
#pragma omp for schedule(dynamic, 4)
    for (int v = 0; v < height; ++v) {
      const std::size_t row = static_cast<std::size_t>(v) * width;
      if (range_gated || plane_gated)
        rowGate(&gate[row], &grid.valid[row], width, g.data());
      if (plane_gated)
        rowFirstNormals(*first, row, width, n0x.data(), n0y.data(), n0z.data());
      // All (2r+1)^2 offsets in one call, in the order the row kernel `moments` would take them,
      // with the sums of each block of centres kept in registers (plane_fit.inc).
      const std::size_t c0 = pad.at(0, v);
      // (Without a gate every valid neighbour counts: no gate, ranges or first normals.)
      const bool gated = range_gated || plane_gated;
      // (Pass 1 has no plane gate: no first normals, so the kernel skips that test.)
      fits.window_moments(&pad.x[c0], &pad.y[c0], &pad.z[c0], &pad.f[c0], gated ? &pad.rho[c0] : nullptr,
                          pad.stride, r, gated ? g.data() : nullptr, plane_gated ? n0x.data() : nullptr,
                          n0y.data(), n0z.data(), range_gated ? 1.0f : 0.0f, width, acc.data());
      // The plane normal is the eigenvector of the smallest eigenvalue of the covariance (in
      // double: with noise close to the pixel spacing the covariance is nearly isotropic and
      // float rounding would decide the normal), a whole row at once (plane_fit.inc).
      fits.normals(acc.data(), &pad.x[c0], &pad.y[c0], &pad.z[c0], &pad.f[c0], view, width, &normals.nx[row],
                   &normals.ny[row], &normals.nz[row]);
    }
  }
}
} // namespace

NormalField
estimateNormalsGated(const Grid& grid, int window, const Viewpoint& viewpoint, int threads,
                     const std::vector<float>& gate, int pass)
{
  NormalField normals;
  estimateNormalsGated(grid, window, viewpoint, threads, gate, pass, normals, nullptr);
  return normals;
}

void
estimateNormalsGated(const Grid& grid, int window, const Viewpoint& viewpoint, int threads,
                     const std::vector<float>& gate, int pass, NormalField& normals, std::vector<float>* planes,
                     NormalField* first)
{
  // Pass 1 (range gate): neighbours whose range differs from p_i's by more than gate[i] are left
  // out: no fit across a depth edge, but on steep slopes few neighbours remain. Pass 2 (plane
  // gate): neighbours farther than gate[i] from pass 1's plane through p_i are left out: the
  // slope is followed and the edge still excluded. Both passes share one padded grid.
  threads = detail::resolveThreads(threads);
  const PaddedGrid pad(grid, window / 2, viewpoint, threads, pass != 0, planes);
  if (pass == 2) {
    // Pass 1's normals in `first` if given: a frame-sized field allocated afresh would be
    // zero-filled and first touched by one thread.
    NormalField own;
    NormalField& pass1 = first ? *first : own;
    fitNormals(grid, pad, window, viewpoint, threads, gate, 1, nullptr, pass1);
    fitNormals(grid, pad, window, viewpoint, threads, gate, 2, &pass1, normals);
    return;
  }
  fitNormals(grid, pad, window, viewpoint, threads, gate, pass, nullptr, normals);
}

} // namespace detail

Grid
presmoothAlongRays(const Grid& grid, int window, float sigma, const Viewpoint& viewpoint, int threads)
{
  return presmoothAlongRays(grid, window, std::vector<float>(grid.size(), sigma), viewpoint, threads);
}

Grid
presmoothAlongRays(const Grid& grid, int window, const std::vector<float>& sigma, const Viewpoint& viewpoint,
                   int threads)
{
  Grid out;
  detail::presmoothAlongRays(grid, window, sigma, viewpoint, threads, out, nullptr);
  return out;
}

void
detail::presmoothAlongRays(const Grid& grid, int window, const std::vector<float>& sigma, const Viewpoint& viewpoint,
                           int threads, Grid& out, std::vector<float>* planes)
{
  const int width = grid.width, height = grid.height;
  const int r = window / 2;
  threads = detail::resolveThreads(threads);
  const detail::PaddedGrid pad(grid, r, viewpoint, threads, true, planes);
  const detail::RowKernels& kernels = detail::rowKernels();
  detail::copyGrid(grid, out, threads);
  (void)threads;
#pragma omp parallel num_threads(threads)
  {
    std::vector<float> num(width), den(width), inv(width);
#pragma omp for schedule(dynamic, 4)
    for (int v = 0; v < height; ++v) {
      const std::size_t row = static_cast<std::size_t>(v) * width;
      for (int u = 0; u < width; ++u)
        inv[u] = sigma[row + u] > 0.0f ? 1.0f / (2.0f * sigma[row + u] * sigma[row + u]) : 0.0f;
      const float* cr = &pad.rho[pad.at(0, v)];
      kernels.window_smoothing(cr, &pad.f[pad.at(0, v)], pad.stride, r, inv.data(), width, num.data(), den.data());
      // rho' = rho + weighted mean range difference; the point stays on its ray. Points without
      // a valid range, sigma or weight keep their coordinates (selected, so that it vectorizes).
      const unsigned char* __restrict valid = &grid.valid[row];
      const float* __restrict sg = &sigma[row];
      const float* __restrict gx = &grid.x[row];
      const float* __restrict gy = &grid.y[row];
      const float* __restrict gz = &grid.z[row];
      float* __restrict ox = &out.x[row];
      float* __restrict oy = &out.y[row];
      float* __restrict oz = &out.z[row];
      const float* __restrict nu = num.data();
      const float* __restrict de = den.data();
      const float vx = viewpoint[0], vy = viewpoint[1], vz = viewpoint[2];
#pragma omp simd
      for (int u = 0; u < width; ++u) {
        const bool moves = (valid[u] != 0) & (cr[u] > 0.0f) & (sg[u] > 0.0f) & (de[u] > 0.0f);
        const float scale = (cr[u] + nu[u] / de[u]) / cr[u];
        const float mx = vx + (gx[u] - vx) * scale, my = vy + (gy[u] - vy) * scale, mz = vz + (gz[u] - vz) * scale;
        ox[u] = moves ? mx : ox[u];
        oy[u] = moves ? my : oy[u];
        oz[u] = moves ? mz : oz[u];
      }
    }
  }
}

} // namespace range_nlm
