// Masks of change between frames (docs/method.md, "A per-pixel test of change"): the pixels whose
// 3 x 3 neighbourhood mostly differs beyond the noise, and their widening by a margin.
#include "internal.h"

#include <algorithm>
#include <cmath>

namespace range_nlm
{

namespace
{
/// changed[i] = 1 where most of the pixels of the 3 x 3 neighbourhood of i with a finite along[j]
/// have beyond(j, along[j]) (see markChangedPixels).
template <typename Beyond>
void
markMostlyBeyond(const std::vector<float>& along, int width, int height, Beyond beyond, int threads,
                 std::vector<unsigned char>& changed)
{
  const std::size_t n = along.size();
  changed.assign(n, 0);
  if (width <= 0 || n != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    return;
  threads = detail::resolveThreads(threads);
  // Per pixel one byte: known (valid in both, finite normal) in the low nibble, beyond the
  // threshold in the high one; their sums over 3 x 3 pixels (at most 9 each, so the nibbles do
  // not carry), along the rows into `rows`, then along the columns.
  std::vector<unsigned char> code(n), rows(n);
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::ptrdiff_t i = 0; i < size; ++i) {
    const float d = along[i];
    const unsigned char known = !std::isnan(d);
    const unsigned char out = beyond(i, d); // false for NaN
    code[i] = static_cast<unsigned char>(known | (out << 4));
  }
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int v = 0; v < height; ++v) {
    const unsigned char* __restrict in = &code[static_cast<std::size_t>(v) * width];
    unsigned char* __restrict out = &rows[static_cast<std::size_t>(v) * width];
    if (width == 1) {
      out[0] = in[0];
      continue;
    }
    out[0] = static_cast<unsigned char>(in[0] + in[1]);
    for (int u = 1; u + 1 < width; ++u)
      out[u] = static_cast<unsigned char>(in[u - 1] + in[u] + in[u + 1]);
    out[width - 1] = static_cast<unsigned char>(in[width - 2] + in[width - 1]);
  }
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int v = 0; v < height; ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * width;
    const unsigned char* __restrict mid = &rows[row];
    const unsigned char* __restrict up = v > 0 ? &rows[row - width] : nullptr;
    const unsigned char* __restrict down = v + 1 < height ? &rows[row + width] : nullptr;
    unsigned char* __restrict out = &changed[row];
    for (int u = 0; u < width; ++u) {
      const unsigned sum = mid[u] + (up ? up[u] : 0u) + (down ? down[u] : 0u);
      const unsigned k = sum & 15u, y = sum >> 4;
      out[u] = k > 0 && 2 * y > k;
    }
  }
}
} // namespace

void
detail::markChangedPixels(const std::vector<float>& along, int width, int height, const float* sigma_a,
                          const float* sigma_b, float ratio, int threads, std::vector<unsigned char>& changed)
{
  const float scale = kChangeSigmas * 1.41421356f * ratio;
  markMostlyBeyond(
      along, width, height,
      [=](std::ptrdiff_t i, float d) { return std::fabs(d) > scale * std::max(sigma_a[i], sigma_b[i]); }, threads,
      changed);
}

void
detail::widenMask(const std::vector<unsigned char>& mask, int width, int height, int radius, int threads,
                  std::vector<unsigned char>& out)
{
  const std::size_t n = mask.size();
  if (radius <= 0 || width <= 0 || height <= 0 || n != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    out = mask;
    return;
  }
  threads = detail::resolveThreads(threads);
  // Separable: the maximum over each row's span, then over each column's.
  std::vector<unsigned char> rows(n);
  out.resize(n);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int v = 0; v < height; ++v) {
    const unsigned char* __restrict in = &mask[static_cast<std::size_t>(v) * width];
    unsigned char* __restrict to = &rows[static_cast<std::size_t>(v) * width];
    for (int u = 0; u < width; ++u) {
      unsigned char any = 0;
      for (int x = std::max(0, u - radius); x <= std::min(width - 1, u + radius); ++x)
        any |= in[x];
      to[u] = any ? 1 : 0;
    }
  }
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int v = 0; v < height; ++v) {
    unsigned char* __restrict to = &out[static_cast<std::size_t>(v) * width];
    for (int u = 0; u < width; ++u) {
      unsigned char any = 0;
      for (int y = std::max(0, v - radius); y <= std::min(height - 1, v + radius); ++y)
        any |= rows[static_cast<std::size_t>(y) * width + u];
      to[u] = any;
    }
  }
}

void
detail::markChangedPixels(const std::vector<float>& along, int width, int height, const float* sigma, float sigmas,
                          int threads, std::vector<unsigned char>& changed)
{
  markMostlyBeyond(
      along, width, height, [=](std::ptrdiff_t i, float d) { return std::fabs(d) > sigmas * sigma[i]; }, threads,
      changed);
}

} // namespace range_nlm
