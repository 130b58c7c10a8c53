// The surface test of the isolated-outlier step: the tolerance's floor (the angle between adjacent
// rays) and which points agree with their neighbours and lie on a surface.
#include "outliers.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace range_nlm
{

float
detail::medianRayAngle(const Grid& grid, const std::vector<float>& rho, int threads)
{
  // A step along the ray of a few pixel footprints is geometry (an edge of a face seen at a
  // grazing angle, a curved silhouette), not an outlier, however small the noise: without this
  // floor a noise-free frame would have its silhouettes taken for outliers.
  const int width = grid.width, height = grid.height;
  // The rows' angles gathered by the threads side by side: the median of the gathered values does
  // not depend on the order they are gathered in.
  std::vector<float> angles;
  const int rows = height > 1 ? (height - 2) / 8 + 1 : 0;
  (void)threads;
#pragma omp parallel num_threads(resolveThreads(threads))
  {
    std::vector<float> mine;
#pragma omp for schedule(static) nowait
    for (int row = 0; row < rows; ++row) {
      const int v = 8 * row;
      for (int u = 0; u + 1 < width; u += 4) {
        const std::size_t i = static_cast<std::size_t>(v) * width + u;
        if (!(rho[i] > 0.0f))
          continue;
        for (const std::size_t j : {i + 1, i + static_cast<std::size_t>(width)})
          if (rho[j] > 0.0f) {
            const float dx = grid.x[j] - grid.x[i], dy = grid.y[j] - grid.y[i], dz = grid.z[j] - grid.z[i];
            const float angle = std::sqrt(dx * dx + dy * dy + dz * dz) / rho[i];
            if (angle < std::numeric_limits<float>::infinity())
              mine.push_back(angle);
          }
      }
    }
#pragma omp critical(range_nlm_ray_angles)
    angles.insert(angles.end(), mine.begin(), mine.end());
  }
  if (angles.empty())
    return 0.0f;
  std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
  return angles[angles.size() / 2];
}

namespace
{
/// Whether point (a, b) agrees with its valid 8-neighbour (c, d): within `tol` (the tolerance at
/// its range r) of the neighbour's range, or of the straight continuation 2 rho_j - rho_j' of the
/// line from the pixel j' beyond the neighbour (a surface steep to the rays), j' other than pixel
/// (skip_a, skip_b).
bool
agrees(const detail::OutlierFrame& frame, int a, int b, int c, int d, float r, float tol, int skip_a, int skip_b)
{
  const float near = frame.rho[static_cast<std::size_t>(d) * frame.width + c];
  if (std::fabs(near - r) <= tol)
    return true;
  const int e = 2 * c - a, f = 2 * d - b;
  if (!frame.validAt(e, f) || (e == skip_a && f == skip_b))
    return false;
  const float beyond = frame.rho[static_cast<std::size_t>(f) * frame.width + e];
  return std::fabs(2.0f * near - beyond - r) <= tol;
}

/// Whether point (a, b) agrees with one of its valid 8-neighbours other than pixel (skip_a, skip_b).
bool
agreesWithANeighbour(const detail::OutlierFrame& frame, int a, int b, int skip_a, int skip_b)
{
  const float r = frame.rho[static_cast<std::size_t>(b) * frame.width + a];
  const float tol = frame.toleranceAt(r);
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du) {
      const int c = a + du, d = b + dv;
      if ((du == 0 && dv == 0) || (c == skip_a && d == skip_b) || !frame.validAt(c, d))
        continue;
      if (agrees(frame, a, b, c, d, r, tol, skip_a, skip_b))
        return true;
    }
  return false;
}
} // namespace

bool
detail::onSurface(const OutlierFrame& frame, int a, int b, int skip_a, int skip_b)
{
  // Two points that agree only with each other (two mixed pixels of a time-of-flight edge at
  // similar ranges, or one in line with a mixed and a surface point by chance) are no surface.
  const float r = frame.rho[static_cast<std::size_t>(b) * frame.width + a];
  const float tol = frame.toleranceAt(r);
  int lone_c = -1, lone_d = -1; // the one neighbour agreed with so far; -1: none
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du) {
      const int c = a + du, d = b + dv;
      if ((du == 0 && dv == 0) || (c == skip_a && d == skip_b) || !frame.validAt(c, d) ||
          !agrees(frame, a, b, c, d, r, tol, skip_a, skip_b))
        continue;
      if (lone_c >= 0)
        return true;
      lone_c = c;
      lone_d = d;
    }
  return lone_c >= 0 && agreesWithANeighbour(frame, lone_c, lone_d, a, b);
}

} // namespace range_nlm
