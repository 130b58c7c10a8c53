// Normal estimation over grid neighbourhoods and the edge-preserving pre-smoothing used for it.
#include "kernel_math.h"

#include <range_nlm/kernel.h>

#include <pcl/common/eigen.h> // pcl::eigen33

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
      float* __restrict cnt = acc.data();
      float* __restrict sx = cnt + width;
      float* __restrict sy = sx + width;
      float* __restrict sz = sy + width;
      float* __restrict sxx = sz + width;
      float* __restrict sxy = sxx + width;
      float* __restrict sxz = sxy + width;
      float* __restrict syy = sxz + width;
      float* __restrict syz = syy + width;
      float* __restrict szz = syz + width;
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
      const float* __restrict cx = &pad.x[c0];
      const float* __restrict cy = &pad.y[c0];
      const float* __restrict cz = &pad.z[c0];
      const float* __restrict cr = &pad.rho[c0];
      const float* __restrict gg = g.data();
      const float* __restrict ax = n0x.data();
      const float* __restrict ay = n0y.data();
      const float* __restrict az = n0z.data();
      const float range_on = range_gated ? 1.0f : 0.0f;
      for (int dv = -r; dv <= r; ++dv)
        for (int du = -r; du <= r; ++du) {
          const std::size_t k0 = pad.at(du, v + dv);
          const float* __restrict qx_ = &pad.x[k0];
          const float* __restrict qy_ = &pad.y[k0];
          const float* __restrict qz_ = &pad.z[k0];
          const float* __restrict qf = &pad.f[k0];
          const float* __restrict qr = &pad.rho[k0];
#pragma omp simd
          for (int u = 0; u < width; ++u) {
            const float qx = qx_[u] - cx[u], qy = qy_[u] - cy[u], qz = qz_[u] - cz[u];
            const float dr = (qr[u] - cr[u]) * range_on;
            const float plane = qx * ax[u] + qy * ay[u] + qz * az[u];
            const float w = (dr * dr <= gg[u] * gg[u] && plane * plane <= gg[u] * gg[u]) ? qf[u] : 0.0f;
            cnt[u] += w;
            sx[u] += w * qx, sy[u] += w * qy, sz[u] += w * qz;
            sxx[u] += w * qx * qx, sxy[u] += w * qx * qy, sxz[u] += w * qx * qz;
            syy[u] += w * qy * qy, syz[u] += w * qy * qz, szz[u] += w * qz * qz;
          }
        }
      for (int u = 0; u < width; ++u) {
        const std::size_t i = row + u;
        if (!grid.valid[i] || cnt[u] < 2.5f)
          continue;
        // The plane normal is the eigenvector of the smallest eigenvalue (PCL's eigen33, as in
        // pcl::solvePlaneParameters, but in double: with noise close to the pixel spacing the
        // covariance is nearly isotropic and float rounding would decide the normal).
        const double inv = 1.0 / cnt[u];
        const double mx = sx[u] * inv, my = sy[u] * inv, mz = sz[u] * inv;
        Eigen::Matrix3d cov;
        cov(0, 0) = sxx[u] * inv - mx * mx;
        cov(0, 1) = cov(1, 0) = sxy[u] * inv - mx * my;
        cov(0, 2) = cov(2, 0) = sxz[u] * inv - mx * mz;
        cov(1, 1) = syy[u] * inv - my * my;
        cov(1, 2) = cov(2, 1) = syz[u] * inv - my * mz;
        cov(2, 2) = szz[u] * inv - mz * mz;
        double eigenvalue = 0.0;
        Eigen::Vector3d normal;
        pcl::eigen33(cov, eigenvalue, normal);
        const double len = normal.norm();
        if (!std::isfinite(len) || len < 0.5)
          continue;
        float nx = float(normal.x() / len), ny = float(normal.y() / len), nz = float(normal.z() / len);
        const float vx = viewpoint[0] - grid.x[i], vy = viewpoint[1] - grid.y[i], vz = viewpoint[2] - grid.z[i];
        if (nx * vx + ny * vy + nz * vz < 0.0f)
          nx = -nx, ny = -ny, nz = -nz;
        normals.nx[i] = nx;
        normals.ny[i] = ny;
        normals.nz[i] = nz;
      }
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
      const float* __restrict cr = &pad.rho[pad.at(0, v)];
      const float* __restrict iv = inv.data();
      float* __restrict nu = num.data();
      float* __restrict de = den.data();
      for (int dv = -r; dv <= r; ++dv)
        for (int du = -r; du <= r; ++du) {
          const std::size_t k0 = pad.at(du, v + dv);
          const float* __restrict qr = &pad.rho[k0];
          const float* __restrict qf = &pad.f[k0];
#pragma omp simd
          for (int u = 0; u < width; ++u) {
            const float d = qr[u] - cr[u];
            const float w = qf[u] * detail::expNonPositiveInline(-d * d * iv[u]);
            nu[u] += w * d;
            de[u] += w;
          }
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
