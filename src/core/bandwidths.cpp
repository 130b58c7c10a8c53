// Automatic bandwidth estimation (docs/method.md, "Automatic bandwidths"): the paper's global
// estimate from windows around sampled points. The range-adaptive noise profile is in
// noise_profile.cpp, the frame-to-frame noise ratio in frame_change.cpp.
#include "internal.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>

namespace range_nlm
{
namespace
{
/// Valid points with a finite normal among `count` (branch-free and with unconditional loads, so
/// that it vectorizes; a NaN or infinite normal fails the comparison).
std::size_t
countCandidates(const unsigned char* __restrict valid, const float* __restrict nx, int count)
{
  int found = 0;
  for (int i = 0; i < count; ++i) {
    const float on = valid[i], n = nx[i];
    found += ((on > 0.0f) & (std::fabs(n) <= std::numeric_limits<float>::max())) ? 1 : 0;
  }
  return static_cast<std::size_t>(found);
}
} // namespace

Bandwidths
estimateBandwidths(const Grid& grid, const NormalField& normals, int search_window, int samples,
                   std::uint64_t seed)
{
  // Candidates are the valid points with a normal, in index order; sample m is the m-th of them.
  // They are counted per block of kBlock points (in parallel), so that the m-th is found by a
  // binary search over the blocks and a scan of one block, without a list of all of them.
  constexpr std::size_t kBlock = 256;
  const std::size_t n = grid.size();
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  // Branch-free (the counting loop vectorizes): a NaN or infinite normal fails the comparison.
  const auto candidate = [&](std::size_t i) {
    return (grid.valid[i] != 0) & (std::fabs(normals.nx[i]) <= std::numeric_limits<float>::max());
  };
  std::vector<std::size_t> first(blocks + 1, 0); // candidates before each block
#pragma omp parallel for schedule(static)
  for (std::size_t b = 0; b < blocks; ++b)
    first[b + 1] = countCandidates(&grid.valid[b * kBlock], &normals.nx[b * kBlock],
                                   static_cast<int>(std::min(n, (b + 1) * kBlock) - b * kBlock));
  for (std::size_t b = 0; b < blocks; ++b)
    first[b + 1] += first[b];
  const std::size_t candidates = first[blocks];
  if (candidates == 0)
    throw UnfilterableFrame("range_nlm: the cloud has no valid point with a normal; nothing to "
                                "estimate the bandwidths from (all points NaN?)");
  // A 64-bit Mersenne twister with our own index mapping: identical on every platform. The
  // samples are visited in index order (they are summed in double; the order only changes
  // rounding far below float precision), which keeps the window reads local.
  std::mt19937_64 rng(seed);
  const std::size_t count = static_cast<std::size_t>(std::max(samples, 0));
  std::vector<std::size_t> order(count);
  for (std::size_t& m : order)
    m = rng() % candidates;
  std::vector<int> picks(count);
#pragma omp parallel for schedule(static)
  for (std::size_t s = 0; s < count; ++s) {
    const std::size_t m = order[s];
    const std::size_t b = static_cast<std::size_t>(std::upper_bound(first.begin(), first.end(), m) - first.begin()) - 1;
    // Whole chunks of the block counted at once (vectorized), then the chunk holding the m-th
    // candidate scanned point by point.
    constexpr std::size_t kChunk = 32;
    const std::size_t end = std::min(n, (b + 1) * kBlock);
    std::size_t seen = first[b], i = b * kBlock;
    for (; i + kChunk <= end; i += kChunk) {
      const std::size_t in_chunk = countCandidates(&grid.valid[i], &normals.nx[i], static_cast<int>(kChunk));
      if (seen + in_chunk > m)
        break;
      seen += in_chunk;
    }
    for (;; ++i)
      if (candidate(i) && seen++ == m)
        break;
    picks[s] = static_cast<int>(i);
  }
  std::sort(picks.begin(), picks.end());
  // Per sample in parallel, then summed in index order (the same sums for any thread count).
  const int r = search_window / 2;
  std::vector<double> extent(count), spread(count);
#pragma omp parallel for schedule(static)
  for (std::size_t s = 0; s < count; ++s) {
    const int k = picks[s];
    const int u = k % grid.width, v = k / grid.width;
    const double nx = normals.nx[k], ny = normals.ny[k], nz = normals.nz[k];
    double max_dist2 = 0.0, sum_h = 0.0, sum_h2 = 0.0;
    int valid = 0;
    for (int jv = std::max(0, v - r); jv <= std::min(grid.height - 1, v + r); ++jv)
      for (int ju = std::max(0, u - r); ju <= std::min(grid.width - 1, u + r); ++ju) {
        // Branch-free (valid and invalid points alternate at holes): invalid points add 0.
        const int j = jv * grid.width + ju;
        const bool ok = grid.valid[j] != 0;
        const double dx = ok ? double(grid.x[j]) - grid.x[k] : 0.0;
        const double dy = ok ? double(grid.y[j]) - grid.y[k] : 0.0;
        const double dz = ok ? double(grid.z[j]) - grid.z[k] : 0.0;
        max_dist2 = std::max(max_dist2, dx * dx + dy * dy + dz * dz);
        const double h = dx * nx + dy * ny + dz * nz;
        sum_h += h;
        sum_h2 += h * h;
        valid += ok ? 1 : 0;
      }
    const double mean = sum_h / valid;
    extent[s] = std::sqrt(max_dist2);
    spread[s] = std::sqrt(std::max(0.0, sum_h2 / valid - mean * mean));
  }
  double sum_mu = 0.0, sum_sigma = 0.0;
  for (std::size_t s = 0; s < count; ++s) {
    sum_mu += extent[s];
    sum_sigma += spread[s];
  }
  Bandwidths b;
  b.mu_d = static_cast<float>(sum_mu / samples);
  b.sigma_s = static_cast<float>(sum_sigma / samples);
  return b;
}

} // namespace range_nlm
