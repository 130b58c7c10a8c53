// Normal estimation over grid neighbourhoods and the edge-preserving pre-smoothing used for it.
#include "kernel_math.h"
#include "kernel_rows.h"
#include "plane_fit.h"

#include <range_nlm/kernel.h>

#include <cmath>
#include <limits>

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
/// A grid copied into a padded SoA layout (border r, invalid points flag 0 and coordinates 0)
/// with the range of every point, so neighbourhood loops run over contiguous rows without
/// bounds checks and vectorize.
struct PaddedGrid
{
  int border, stride;
  std::vector<float> x, y, z, f, rho;
  PaddedGrid(const Grid& g, int r, const Viewpoint& viewpoint) : border(r), stride(g.width + 2 * r)
  {
    const std::size_t n = static_cast<std::size_t>(stride) * (g.height + 2 * r);
    x.assign(n, 0.0f), y.assign(n, 0.0f), z.assign(n, 0.0f), f.assign(n, 0.0f), rho.assign(n, 0.0f);
    for (int v = 0; v < g.height; ++v)
      for (int u = 0; u < g.width; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * g.width + u;
        if (!g.valid[i])
          continue;
        const std::size_t k = at(u, v);
        x[k] = g.x[i], y[k] = g.y[i], z[k] = g.z[i], f[k] = 1.0f;
        const float dx = g.x[i] - viewpoint[0], dy = g.y[i] - viewpoint[1], dz = g.z[i] - viewpoint[2];
        rho[k] = std::sqrt(dx * dx + dy * dy + dz * dz);
      }
  }
  std::size_t at(int u, int v) const { return static_cast<std::size_t>(v + border) * stride + (u + border); }
};
} // namespace

NormalField
estimateNormalsGated(const Grid& grid, int window, const Viewpoint& viewpoint, int threads,
                     const std::vector<float>& gate, int pass)
{
  // Pass 1 (range gate): neighbours whose range differs from p_i's by more than gate[i] are left
  // out: no fit across a depth edge, but on steep slopes few neighbours remain. Pass 2 (plane
  // gate): neighbours farther than gate[i] from pass 1's plane through p_i are left out: the
  // slope is followed and the edge still excluded.
  const bool range_gated = pass == 1;
  const bool plane_gated = pass == 2;
  const NormalField first =
      plane_gated ? estimateNormalsGated(grid, window, viewpoint, threads, gate, 1) : NormalField();
  const int width = grid.width, height = grid.height;
  const int r = window / 2;
  const PaddedGrid pad(grid, r, viewpoint);
  const RowKernels& kernels = rowKernels();
  const PlaneFitKernels& fits = planeFitKernels();
  const float view[3] = {viewpoint[0], viewpoint[1], viewpoint[2]};
  NormalField normals;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  normals.nx.assign(grid.size(), nan);
  normals.ny.assign(grid.size(), nan);
  normals.nz.assign(grid.size(), nan);
  threads = detail::resolveThreads(threads);
  (void)threads;
#pragma omp parallel num_threads(threads)
  {
    // Per row: moments of the neighbourhood relative to p_i (a local origin keeps the float
    // sums well conditioned), accumulated one neighbour offset at a time over the whole row.
    std::vector<float> acc(10 * static_cast<std::size_t>(width));
    std::vector<float> g(width, 1e30f), n0x(width, 0.0f), n0y(width, 0.0f), n0z(width, 0.0f);
#pragma omp for schedule(dynamic, 4)
    for (int v = 0; v < height; ++v) {
      std::fill(acc.begin(), acc.end(), 0.0f);
      const std::size_t row = static_cast<std::size_t>(v) * width;
      for (int u = 0; u < width; ++u) {
        const std::size_t i = row + u;
        g[u] = (range_gated || plane_gated) && grid.valid[i] ? gate[i] : 1e30f;
        const bool has = plane_gated && std::isfinite(first.nx[i]);
        n0x[u] = has ? first.nx[i] : 0.0f;
        n0y[u] = has ? first.ny[i] : 0.0f;
        n0z[u] = has ? first.nz[i] : 0.0f;
      }
      const std::size_t c0 = pad.at(0, v);
      const RowPointers centre{&pad.x[c0], &pad.y[c0], &pad.z[c0], &pad.f[c0]};
      for (int dv = -r; dv <= r; ++dv)
        for (int du = -r; du <= r; ++du) {
          const std::size_t k0 = pad.at(du, v + dv);
          kernels.moments(centre, &pad.rho[c0], RowPointers{&pad.x[k0], &pad.y[k0], &pad.z[k0], &pad.f[k0]},
                          &pad.rho[k0], g.data(), n0x.data(), n0y.data(), n0z.data(), range_gated ? 1.0f : 0.0f,
                          width, acc.data());
        }
      // The plane normal is the eigenvector of the smallest eigenvalue of the covariance (in
      // double: with noise close to the pixel spacing the covariance is nearly isotropic and
      // float rounding would decide the normal), a whole row at once (plane_fit.inc).
      fits.normals(acc.data(), &pad.x[c0], &pad.y[c0], &pad.z[c0], &pad.f[c0], view, width, &normals.nx[row],
                   &normals.ny[row], &normals.nz[row]);
    }
  }
  return normals;
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
  const int width = grid.width, height = grid.height;
  const int r = window / 2;
  const detail::PaddedGrid pad(grid, r, viewpoint);
  const detail::RowKernels& kernels = detail::rowKernels();
  Grid out = grid;
  threads = detail::resolveThreads(threads);
  (void)threads;
#pragma omp parallel num_threads(threads)
  {
    std::vector<float> num(width), den(width), inv(width);
#pragma omp for schedule(dynamic, 4)
    for (int v = 0; v < height; ++v) {
      const std::size_t row = static_cast<std::size_t>(v) * width;
      for (int u = 0; u < width; ++u)
        inv[u] = sigma[row + u] > 0.0f ? 1.0f / (2.0f * sigma[row + u] * sigma[row + u]) : 0.0f;
      std::fill(num.begin(), num.end(), 0.0f);
      std::fill(den.begin(), den.end(), 0.0f);
      const float* cr = &pad.rho[pad.at(0, v)];
      for (int dv = -r; dv <= r; ++dv)
        for (int du = -r; du <= r; ++du) {
          const std::size_t k0 = pad.at(du, v + dv);
          kernels.smoothing(cr, &pad.rho[k0], &pad.f[k0], inv.data(), width, num.data(), den.data());
        }
      for (int u = 0; u < width; ++u) {
        const std::size_t i = row + u;
        if (!grid.valid[i] || !(cr[u] > 0.0f) || !(sigma[i] > 0.0f) || !(den[u] > 0.0f))
          continue;
        // rho' = rho + weighted mean range difference; the point stays on its ray.
        const float scale = (cr[u] + num[u] / den[u]) / cr[u];
        out.x[i] = viewpoint[0] + (grid.x[i] - viewpoint[0]) * scale;
        out.y[i] = viewpoint[1] + (grid.y[i] - viewpoint[1]) * scale;
        out.z[i] = viewpoint[2] + (grid.z[i] - viewpoint[2]) * scale;
      }
    }
  }
  return out;
}

} // namespace range_nlm
