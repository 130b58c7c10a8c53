#include <range_nlm/core/grid.h>

#include <cmath>
#include <limits>

namespace range_nlm
{

Grid::Grid(int w, int h) : width(w), height(h)
{
  const std::size_t n = size();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  x.assign(n, nan);
  y.assign(n, nan);
  z.assign(n, nan);
  valid.assign(n, 0);
}

std::size_t
Grid::countValid() const
{
  std::size_t count = 0;
  for (unsigned char v : valid)
    count += v;
  return count;
}

Grid
Grid::fromInterleaved(const float* data, int width, int height, std::size_t stride_floats)
{
  Grid grid(width, height);
  const std::size_t n = grid.size();
  for (std::size_t i = 0; i < n; ++i) {
    const float* p = data + i * stride_floats;
    grid.x[i] = p[0];
    grid.y[i] = p[1];
    grid.z[i] = p[2];
  }
  grid.updateValidity();
  return grid;
}

void
Grid::updateValidity()
{
  const std::size_t n = size();
  valid.resize(n);
  const float nan = std::numeric_limits<float>::quiet_NaN();
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i) {
    const bool ok = std::isfinite(x[i]) && std::isfinite(y[i]) && std::isfinite(z[i]);
    valid[i] = ok ? 1 : 0;
    if (!ok)
      x[i] = y[i] = z[i] = nan;
  }
}

} // namespace range_nlm
