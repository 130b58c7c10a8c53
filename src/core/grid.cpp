#include <range_nlm/core/grid.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace range_nlm
{

namespace
{
/// Points from which countValid counts in parallel (below, starting the threads costs more).
constexpr std::ptrdiff_t kParallelCount = 1 << 16;
} // namespace

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
  // Called on whole frames several times per filter call: in parallel (an exact integer sum).
  std::size_t count = 0;
  const unsigned char* __restrict flags = valid.data();
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(valid.size());
#pragma omp parallel for simd schedule(static) reduction(+ : count) if (n >= kParallelCount)
  for (std::ptrdiff_t i = 0; i < n; ++i)
    count += flags[i];
  return count;
}

std::ptrdiff_t
Grid::assignInterleaved(const float* data, int width_, int height_, std::size_t stride_floats)
{
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(width_) * height_;
  width = width_;
  height = height_;
  // Every element is written below: resizing to the size it already has costs nothing.
  x.resize(n);
  y.resize(n);
  z.resize(n);
  valid.resize(n);
  // Branch-free on the bits of the coordinates (a branch per point mispredicts wherever valid and
  // invalid points alternate): |x| below the exponent's all-ones pattern is finite, equal to it is
  // infinite. The position of an infinity is looked for only once one was seen.
  const std::uint32_t nan_bits = 0x7fc00000u; // quiet NaN
  const std::uint32_t inf_bits = 0x7f800000u; // |x| of an infinity; finite below
  std::uint32_t infinite = 0;
  float* __restrict gx = x.data();
  float* __restrict gy = y.data();
  float* __restrict gz = z.data();
  unsigned char* __restrict gv = valid.data();
  const std::ptrdiff_t stride = static_cast<std::ptrdiff_t>(stride_floats);
#pragma omp parallel for simd schedule(static) reduction(| : infinite)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const float* p = data + i * stride;
    std::uint32_t bx, by, bz;
    std::memcpy(&bx, p, sizeof bx);
    std::memcpy(&by, p + 1, sizeof by);
    std::memcpy(&bz, p + 2, sizeof bz);
    const std::uint32_t ax = bx & 0x7fffffffu, ay = by & 0x7fffffffu, az = bz & 0x7fffffffu;
    const std::uint32_t ok = std::uint32_t{ax < inf_bits} & std::uint32_t{ay < inf_bits} & std::uint32_t{az < inf_bits};
    infinite |= std::uint32_t{ax == inf_bits} | std::uint32_t{ay == inf_bits} | std::uint32_t{az == inf_bits};
    const std::uint32_t keep = 0u - ok;
    bx = (bx & keep) | (nan_bits & ~keep);
    by = (by & keep) | (nan_bits & ~keep);
    bz = (bz & keep) | (nan_bits & ~keep);
    std::memcpy(&gx[i], &bx, sizeof bx);
    std::memcpy(&gy[i], &by, sizeof by);
    std::memcpy(&gz[i], &bz, sizeof bz);
    gv[i] = static_cast<unsigned char>(ok);
  }
  for (std::ptrdiff_t i = 0; infinite && i < n; ++i) {
    const float* p = data + i * stride;
    if (std::isinf(p[0]) || std::isinf(p[1]) || std::isinf(p[2]))
      return i;
  }
  return -1;
}

Grid
Grid::fromInterleaved(const float* data, int width, int height, std::size_t stride_floats)
{
  Grid grid;
  grid.assignInterleaved(data, width, height, stride_floats);
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

void
Grid::assignValidated(const Grid& from)
{
  width = from.width;
  height = from.height;
  const std::size_t n = from.x.size();
  x.resize(n);
  y.resize(n);
  z.resize(n);
  valid.resize(n);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t i = 0; i < size; ++i) {
    const float px = from.x[i], py = from.y[i], pz = from.z[i];
    const bool ok = std::isfinite(px) && std::isfinite(py) && std::isfinite(pz);
    x[i] = ok ? px : nan;
    y[i] = ok ? py : nan;
    z[i] = ok ? pz : nan;
    valid[i] = ok ? 1 : 0;
  }
}

} // namespace range_nlm
