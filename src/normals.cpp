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
  std::vector<float> rho;
  if (range_gated) {
    rho.assign(grid.size(), 0.0f);
    for (std::size_t i = 0; i < grid.size(); ++i)
      if (grid.valid[i]) {
        const float dx = grid.x[i] - viewpoint[0], dy = grid.y[i] - viewpoint[1], dz = grid.z[i] - viewpoint[2];
        rho[i] = std::sqrt(dx * dx + dy * dy + dz * dz);
      }
  }
  const int width = grid.width, height = grid.height;
  const int r = window / 2;
  NormalField normals;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  normals.nx.assign(grid.size(), nan);
  normals.ny.assign(grid.size(), nan);
  normals.nz.assign(grid.size(), nan);
  threads = detail::resolveThreads(threads);
  (void)threads;
#pragma omp parallel for schedule(dynamic, 8) num_threads(threads)
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const int i = v * width + u;
      if (!grid.valid[i])
        continue;
      // Moments relative to p_i (a local origin keeps the covariance well conditioned).
      double s[3] = {0, 0, 0}, ss[6] = {0, 0, 0, 0, 0, 0};
      int count = 0;
      for (int jv = std::max(0, v - r); jv <= std::min(height - 1, v + r); ++jv)
        for (int ju = std::max(0, u - r); ju <= std::min(width - 1, u + r); ++ju) {
          const int j = jv * width + ju;
          if (!grid.valid[j])
            continue;
          if (range_gated && std::fabs(rho[j] - rho[i]) > gate[i])
            continue;
          if (plane_gated && std::isfinite(first.nx[i]) &&
              std::fabs((grid.x[j] - grid.x[i]) * first.nx[i] + (grid.y[j] - grid.y[i]) * first.ny[i] +
                        (grid.z[j] - grid.z[i]) * first.nz[i]) > gate[i])
            continue;
          const double qx = double(grid.x[j]) - grid.x[i];
          const double qy = double(grid.y[j]) - grid.y[i];
          const double qz = double(grid.z[j]) - grid.z[i];
          s[0] += qx, s[1] += qy, s[2] += qz;
          ss[0] += qx * qx, ss[1] += qx * qy, ss[2] += qx * qz;
          ss[3] += qy * qy, ss[4] += qy * qz, ss[5] += qz * qz;
          ++count;
        }
      if (count < 3)
        continue;
      const double inv = 1.0 / count;
      const double mx = s[0] * inv, my = s[1] * inv, mz = s[2] * inv;
      // The plane normal is the eigenvector of the smallest eigenvalue (PCL's eigen33, as in
      // pcl::solvePlaneParameters, but in double: with noise close to the pixel spacing the 3x3
      // covariance is nearly isotropic and float rounding would decide the normal).
      Eigen::Matrix3d cov;
      cov(0, 0) = ss[0] * inv - mx * mx;
      cov(0, 1) = cov(1, 0) = ss[1] * inv - mx * my;
      cov(0, 2) = cov(2, 0) = ss[2] * inv - mx * mz;
      cov(1, 1) = ss[3] * inv - my * my;
      cov(1, 2) = cov(2, 1) = ss[4] * inv - my * mz;
      cov(2, 2) = ss[5] * inv - mz * mz;
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
  const std::size_t n = grid.size();
  std::vector<float> rho(n, 0.0f);
  for (std::size_t i = 0; i < n; ++i)
    if (grid.valid[i]) {
      const float dx = grid.x[i] - viewpoint[0], dy = grid.y[i] - viewpoint[1], dz = grid.z[i] - viewpoint[2];
      rho[i] = std::sqrt(dx * dx + dy * dy + dz * dz);
    }
  Grid out = grid;
  threads = detail::resolveThreads(threads);
  (void)threads;
#pragma omp parallel for schedule(dynamic, 8) num_threads(threads)
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const int i = v * width + u;
      if (!grid.valid[i] || !(rho[i] > 0.0f) || !(sigma[i] > 0.0f))
        continue;
      const float inv = 1.0f / (2.0f * sigma[i] * sigma[i]);
      float num = 0.0f, den = 0.0f;
      for (int jv = std::max(0, v - r); jv <= std::min(height - 1, v + r); ++jv) {
        const int row = jv * width;
        for (int ju = std::max(0, u - r); ju <= std::min(width - 1, u + r); ++ju) {
          const int j = row + ju;
          const float d = rho[j] - rho[i];
          const float w = grid.valid[j] ? detail::expNonPositiveInline(-d * d * inv) : 0.0f;
          num += w * d;
          den += w;
        }
      }
      const float scale = (rho[i] + num / den) / rho[i];
      out.x[i] = viewpoint[0] + (grid.x[i] - viewpoint[0]) * scale;
      out.y[i] = viewpoint[1] + (grid.y[i] - viewpoint[1]) * scale;
      out.z[i] = viewpoint[2] + (grid.z[i] - viewpoint[2]) * scale;
    }
  }
  return out;
}

} // namespace range_nlm
