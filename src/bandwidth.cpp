// Automatic bandwidth estimation (METHOD.md step 4).
#include <range_nlm/kernel.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace range_nlm
{

Bandwidths
estimateBandwidths(const Grid& grid, const NormalField& normals, int search_window, int samples,
                   std::uint64_t seed)
{
  std::vector<int> candidates;
  candidates.reserve(grid.size());
  for (std::size_t i = 0; i < grid.size(); ++i)
    if (grid.valid[i] && std::isfinite(normals.nx[i]))
      candidates.push_back(static_cast<int>(i));
  if (candidates.empty())
    throw std::invalid_argument("range_nlm: the cloud has no valid point with a normal; nothing to "
                                "estimate the bandwidths from (all points NaN?)");
  // A 64-bit Mersenne twister with our own index mapping: identical on every platform.
  std::mt19937_64 rng(seed);
  const int r = search_window / 2;
  double sum_mu = 0.0, sum_sigma = 0.0;
  for (int s = 0; s < samples; ++s) {
    const int k = candidates[rng() % candidates.size()];
    const int u = k % grid.width, v = k / grid.width;
    const double nx = normals.nx[k], ny = normals.ny[k], nz = normals.nz[k];
    double max_dist2 = 0.0, sum_h = 0.0, sum_h2 = 0.0;
    int count = 0;
    for (int jv = std::max(0, v - r); jv <= std::min(grid.height - 1, v + r); ++jv)
      for (int ju = std::max(0, u - r); ju <= std::min(grid.width - 1, u + r); ++ju) {
        const int j = jv * grid.width + ju;
        if (!grid.valid[j])
          continue;
        const double dx = double(grid.x[j]) - grid.x[k];
        const double dy = double(grid.y[j]) - grid.y[k];
        const double dz = double(grid.z[j]) - grid.z[k];
        max_dist2 = std::max(max_dist2, dx * dx + dy * dy + dz * dz);
        const double h = dx * nx + dy * ny + dz * nz;
        sum_h += h;
        sum_h2 += h * h;
        ++count;
      }
    const double mean = sum_h / count;
    sum_mu += std::sqrt(max_dist2);
    sum_sigma += std::sqrt(std::max(0.0, sum_h2 / count - mean * mean));
  }
  Bandwidths b;
  b.mu_d = static_cast<float>(sum_mu / samples);
  b.sigma_s = static_cast<float>(sum_sigma / samples);
  return b;
}

} // namespace range_nlm
