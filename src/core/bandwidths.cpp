// Automatic bandwidth estimation (docs/method.md, "Automatic bandwidths"): the paper's global
// estimate, the range-adaptive noise profile and the frame-to-frame noise ratio.
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

#include <pcl/common/eigen.h>

namespace range_nlm
{
namespace
{
float
interpolate(const std::vector<float>& xs, const std::vector<float>& ys, float x)
{
  if (xs.empty())
    return 0.0f;
  if (x <= xs.front())
    return ys.front();
  if (x >= xs.back())
    return ys.back();
  const auto it = std::upper_bound(xs.begin(), xs.end(), x);
  const std::size_t hi = static_cast<std::size_t>(it - xs.begin()), lo = hi - 1;
  const float t = (x - xs[lo]) / std::max(xs[hi] - xs[lo], 1e-30f);
  return ys[lo] + t * (ys[hi] - ys[lo]);
}

float
medianOf(std::vector<float> v)
{
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  return v[mid];
}
} // namespace

namespace
{
/// detail::interpolateProfile, with the second profile (ys2, out2) if Second (then both non-null).
template <bool Second>
void
interpolateProfiles(const std::vector<float>& xs, const std::vector<float>& ys, const float* x, float* out,
                    std::size_t n, const std::vector<float>* ys2, float* out2)
{
  // interpolate() for a block of points at a time, branch-free so that it vectorizes: the bin
  // [xs[lo], xs[lo + 1]] of x is found by a scan over the (strictly increasing) ranges instead of
  // a binary search per point, and the same arithmetic follows. A second profile over the same
  // ranges (ys2) shares the scan.
  const std::size_t bins = xs.size();
  const float front = xs.front(), back = xs.back();
  const std::vector<float>& zs = Second ? *ys2 : ys;
  constexpr std::size_t kBlock = 256;
  // The bin's ends as bits, chosen with masks (GCC turns a select into a branch here).
  std::uint32_t xl[kBlock], xh[kBlock], yl[kBlock], yh[kBlock], zl[kBlock], zh[kBlock];
  const auto bits = [](float f) { return __builtin_bit_cast(std::uint32_t, f); };
  const auto value = [](std::uint32_t b) { return __builtin_bit_cast(float, b); };
  for (std::size_t i0 = 0; i0 < n; i0 += kBlock) {
    const int m = static_cast<int>(std::min(kBlock, n - i0));
    const float* __restrict xv = x + i0;
    // The profile (xs, v) at the block's points into o, from the chosen bins' values lo, hi.
    const auto finish = [&](const std::vector<float>& v, const std::uint32_t* lo, const std::uint32_t* hi,
                            float* __restrict o) {
      const float first = v.front(), last = v.back();
      for (int i = 0; i < m; ++i) {
        const float lx = value(xl[i]), ly = value(lo[i]), hx = value(xh[i]), hy = value(hi[i]);
        const float gap = hx - lx;
        const float t = (xv[i] - lx) / (gap < 1e-30f ? 1e-30f : gap);
        const float mid = bins == 1 ? first : ly + t * (hy - ly);
        o[i] = xv[i] <= front ? first : (xv[i] >= back ? last : mid);
      }
    };
    const std::size_t next = bins > 1 ? 1 : 0;
    for (int i = 0; i < m; ++i) {
      xl[i] = bits(xs[0]), xh[i] = bits(xs[next]), yl[i] = bits(ys[0]), yh[i] = bits(ys[next]);
      if (Second)
        zl[i] = bits(zs[0]), zh[i] = bits(zs[next]);
    }
    for (std::size_t b = 1; b + 1 < bins; ++b) {
      const float xb = xs[b];
      const std::uint32_t bxb = bits(xb), byb = bits(ys[b]), bzb = bits(zs[b]);
      const std::uint32_t bxn = bits(xs[b + 1]), byn = bits(ys[b + 1]), bzn = bits(zs[b + 1]);
      for (int i = 0; i < m; ++i) {
        const std::uint32_t past = 0u - static_cast<std::uint32_t>(xb <= xv[i]);
        xl[i] = (bxb & past) | (xl[i] & ~past), xh[i] = (bxn & past) | (xh[i] & ~past);
        yl[i] = (byb & past) | (yl[i] & ~past), yh[i] = (byn & past) | (yh[i] & ~past);
        if (Second)
          zl[i] = (bzb & past) | (zl[i] & ~past), zh[i] = (bzn & past) | (zh[i] & ~past);
      }
    }
    finish(ys, yl, yh, out + i0);
    if (Second)
      finish(zs, zl, zh, out2 + i0);
  }
}
} // namespace

void
detail::interpolateProfile(const std::vector<float>& xs, const std::vector<float>& ys, const float* x, float* out,
                           std::size_t n, const std::vector<float>* ys2, float* out2)
{
  const bool second = ys2 && out2;
  if (xs.empty()) {
    std::fill(out, out + n, 0.0f);
    if (second)
      std::fill(out2, out2 + n, 0.0f);
    return;
  }
  if (second)
    interpolateProfiles<true>(xs, ys, x, out, n, ys2, out2);
  else
    interpolateProfiles<false>(xs, ys, x, out, n, nullptr, nullptr);
}

float
NoiseProfile::sigmaAt(float rho) const
{
  return interpolate(range, sigma, rho);
}

float
NoiseProfile::extentAt(float rho) const
{
  return interpolate(range, extent, rho);
}

NoiseProfile
estimateNoiseProfile(const Grid& grid, int search_window, int samples, std::uint64_t seed,
                     const Viewpoint& viewpoint)
{
  return detail::estimateNoiseProfile(grid, search_window, samples, seed, viewpoint, 1);
}

NoiseProfile
detail::estimateNoiseProfile(const Grid& grid, int search_window, int samples, std::uint64_t seed,
                             const Viewpoint& viewpoint, int threads)
{
  // The samples are the valid points of ranks rng() % valid, in index order. Valid points are
  // counted per chunk of 64 pixels (a vectorized sum), and each rank is found in its chunk.
  constexpr std::size_t kChunk = 64;
  const std::size_t n = grid.size(), chunks = (n + kChunk - 1) / kChunk;
  std::vector<std::uint32_t> before(chunks + 1, 0u); // valid points before each chunk
  for (std::size_t c = 0; c < chunks; ++c) {
    const unsigned char* __restrict v = grid.valid.data() + c * kChunk;
    const std::size_t m = std::min(kChunk, n - c * kChunk);
    std::uint32_t count = 0;
    for (std::size_t i = 0; i < m; ++i)
      count += v[i] != 0;
    before[c + 1] = before[c] + count;
  }
  const std::uint64_t valid_count = before[chunks];
  if (valid_count == 0)
    throw UnfilterableFrame("range_nlm: the cloud has no valid point; nothing to estimate the noise from");
  const auto validOfRank = [&](std::uint64_t rank) {
    const std::size_t c =
        static_cast<std::size_t>(std::upper_bound(before.begin(), before.end(), rank) - before.begin()) - 1;
    std::uint64_t left = rank - before[c];
    std::size_t i = c * kChunk;
    for (;; ++i)
      if (grid.valid[i] && left-- == 0)
        return static_cast<int>(i);
  };
  std::mt19937_64 rng(seed);
  // At least the 3 x 3 neighbourhood: a plane fit needs 4 points, and a 1 x 1 search window (which
  // moves nothing) must not make the noise estimate impossible.
  const int r = std::max(1, search_window / 2);
  struct Sample
  {
    float rho, sigma, extent;
  };
  // The samples are drawn in order, then evaluated in parallel, each into its own slot; the
  // slots of windows that qualify are kept in sample order.
  std::vector<int> picked(static_cast<std::size_t>(std::max(samples, 0)));
  for (int& k : picked)
    k = validOfRank(rng() % valid_count);
  std::vector<Sample> slots(picked.size());
  std::vector<unsigned char> kept(picked.size(), 0);
  (void)threads;
#pragma omp parallel for schedule(dynamic, 16) num_threads(detail::resolveThreads(threads))
  for (int s = 0; s < samples; ++s) {
    const int k = picked[s];
    const int u = k % grid.width, v = k / grid.width;
    double sum[3] = {0, 0, 0}, sq[6] = {0, 0, 0, 0, 0, 0}, max_dist2 = 0.0;
    int count = 0;
    for (int jv = std::max(0, v - r); jv <= std::min(grid.height - 1, v + r); ++jv)
      for (int ju = std::max(0, u - r); ju <= std::min(grid.width - 1, u + r); ++ju) {
        const int j = jv * grid.width + ju;
        if (!grid.valid[j])
          continue;
        const double qx = double(grid.x[j]) - grid.x[k], qy = double(grid.y[j]) - grid.y[k],
                     qz = double(grid.z[j]) - grid.z[k];
        sum[0] += qx, sum[1] += qy, sum[2] += qz;
        sq[0] += qx * qx, sq[1] += qx * qy, sq[2] += qx * qz, sq[3] += qy * qy, sq[4] += qy * qz, sq[5] += qz * qz;
        max_dist2 = std::max(max_dist2, qx * qx + qy * qy + qz * qz);
        ++count;
      }
    if (count < 4)
      continue;
    const double inv = 1.0 / count;
    const double mx = sum[0] * inv, my = sum[1] * inv, mz = sum[2] * inv;
    Eigen::Matrix3d cov;
    cov << sq[0] * inv - mx * mx, sq[1] * inv - mx * my, sq[2] * inv - mx * mz, sq[1] * inv - mx * my,
        sq[3] * inv - my * my, sq[4] * inv - my * mz, sq[2] * inv - mx * mz, sq[4] * inv - my * mz,
        sq[5] * inv - mz * mz;
    double smallest = 0.0;
    Eigen::Vector3d normal;
    pcl::eigen33(cov, smallest, normal);
    const double dx = grid.x[k] - viewpoint[0], dy = grid.y[k] - viewpoint[1], dz = grid.z[k] - viewpoint[2];
    const double rho = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!(rho > 0.0))
      continue;
    slots[s] = Sample{float(rho), float(std::sqrt(std::max(0.0, smallest))), float(std::sqrt(max_dist2) / rho)};
    kept[s] = 1;
  }
  std::vector<Sample> found;
  found.reserve(picked.size());
  for (std::size_t s = 0; s < picked.size(); ++s)
    if (kept[s])
      found.push_back(slots[s]);
  if (found.empty())
    throw UnfilterableFrame("range_nlm: no sampled window has 4 valid points; cannot estimate the noise");
  std::sort(found.begin(), found.end(), [](const Sample& a, const Sample& b) { return a.rho < b.rho; });
  const std::size_t bins = std::clamp<std::size_t>(found.size() / 64, 1, 8);
  NoiseProfile profile;
  for (std::size_t b = 0; b < bins; ++b) {
    const std::size_t lo = b * found.size() / bins, hi = (b + 1) * found.size() / bins;
    std::vector<float> rho, sigma, extent;
    for (std::size_t i = lo; i < hi; ++i) {
      rho.push_back(found[i].rho);
      sigma.push_back(found[i].sigma);
      extent.push_back(found[i].extent);
    }
    profile.range.push_back(medianOf(rho));
    profile.sigma.push_back(medianOf(sigma));
    profile.extent.push_back(medianOf(extent));
  }
  // Equal ranges (e.g. a fronto-parallel plane) would make interpolation degenerate.
  for (std::size_t b = 1; b < profile.range.size(); ++b)
    profile.range[b] = std::max(profile.range[b], std::nextafter(profile.range[b - 1], 1e30f));
  return profile;
}

bool
framesMoved(const Grid& a, const NormalField& normals_a, const Grid& b)
{
  return detail::framesMoved(a, normals_a, b, 1);
}

bool
detail::framesMoved(const Grid& a, const NormalField& normals_a, const Grid& b, int threads)
{
  return detail::compareFrames(a, normals_a, b, nullptr, true, threads).moved;
}

float
detail::medianOfNonNegative(const float* values, const unsigned char* mask, std::size_t n, int threads,
                            std::size_t* count)
{
  // Non-negative floats order as their bits do: a histogram of the upper 16 bits finds the bin
  // holding the median's rank, and only that bin's values are copied and selected from (a tenth
  // of the time of std::nth_element over all of them at VGA size).
  constexpr std::size_t kBins = 1u << 16;
  const auto bin = [](float f) { return __builtin_bit_cast(std::uint32_t, f) >> 16; };
  const auto counted = [&](std::ptrdiff_t i) { return (!mask || mask[i]) && values[i] >= 0.0f; };
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(n);
  std::vector<std::uint32_t> histogram(kBins, 0u);
#pragma omp parallel num_threads(detail::resolveThreads(threads))
  {
    std::vector<std::uint32_t> mine(kBins, 0u);
#pragma omp for schedule(static) nowait
    for (std::ptrdiff_t i = 0; i < size; ++i)
      if (counted(i))
        ++mine[bin(values[i])];
#pragma omp critical(range_nlm_median_histogram)
    for (std::size_t b = 0; b < kBins; ++b)
      histogram[b] += mine[b];
  }
  std::size_t total = 0;
  for (std::uint32_t h : histogram)
    total += h;
  if (count)
    *count = total;
  if (total == 0)
    return std::numeric_limits<float>::quiet_NaN();
  const std::size_t rank = total / 2;
  std::size_t below = 0, chosen = 0;
  for (; below + histogram[chosen] <= rank; ++chosen)
    below += histogram[chosen];
  std::vector<float> in_bin;
  in_bin.reserve(histogram[chosen]);
  for (std::ptrdiff_t i = 0; i < size; ++i)
    if (counted(i) && bin(values[i]) == chosen)
      in_bin.push_back(values[i]);
  const std::ptrdiff_t k = static_cast<std::ptrdiff_t>(rank - below);
  std::nth_element(in_bin.begin(), in_bin.begin() + k, in_bin.end());
  return in_bin[k];
}

void
detail::alongNormals(const Grid& a, const NormalField& normals_a, const Grid& b, int threads, std::vector<float>& along)
{
  const std::size_t n = a.size();
  along.resize(n);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel for schedule(static) num_threads(detail::resolveThreads(threads))
  for (std::ptrdiff_t i = 0; i < size; ++i)
    along[i] = a.valid[i] && b.valid[i] && std::isfinite(normals_a.nx[i])
                   ? (b.x[i] - a.x[i]) * normals_a.nx[i] + (b.y[i] - a.y[i]) * normals_a.ny[i] +
                         (b.z[i] - a.z[i]) * normals_a.nz[i]
                   : nan;
}

detail::FrameComparison
detail::compareFrames(const Grid& a, const NormalField& normals_a, const Grid& b, const float* sigma_b,
                      bool test_motion, int threads)
{
  if (a.size() != b.size() || normals_a.size() != a.size() || a.width <= 0)
    return FrameComparison();
  std::vector<float> along;
  detail::alongNormals(a, normals_a, b, threads, along);
  return detail::compareAlong(along, a.width, a.height, sigma_b, test_motion, threads);
}

detail::FrameComparison
detail::compareAlong(const std::vector<float>& along, int width, int height, const float* sigma_b, bool test_motion,
                     int threads)
{
  FrameComparison result;
  const std::size_t n = along.size();
  if (width <= 0 || n != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    return result;
  threads = detail::resolveThreads(threads);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  if (test_motion) {
    // Blocks of about 1/20 of the width (32 pixels at 640): many noise blobs each, so that their
    // median difference is near 0 for noise, however correlated, and near the motion where the
    // camera or the scene moved.
    const int block = std::max(8, width / 20);
    const int columns = width / block, rows = height / block;
    // Each block by one thread into its own slot (NaN: too few pixels); a median does not depend
    // on the order of its values.
    std::vector<float> block_offsets(static_cast<std::size_t>(columns) * rows, nan), block_spreads(block_offsets);
#pragma omp parallel num_threads(threads)
    {
      std::vector<float> in_block;
#pragma omp for schedule(dynamic, 4)
      for (int t = 0; t < columns * rows; ++t) {
        const int v0 = (t / columns) * block, u0 = (t % columns) * block;
        in_block.clear();
        for (int v = v0; v < v0 + block; ++v)
          for (int u = u0; u < u0 + block; ++u) {
            const float d = along[static_cast<std::size_t>(v) * width + u];
            if (!std::isnan(d))
              in_block.push_back(d);
          }
        if (in_block.size() < static_cast<std::size_t>(block * block / 2))
          continue;
        const float m = medianOf(in_block);
        for (float& d : in_block)
          d = std::fabs(d - m);
        block_offsets[t] = std::fabs(m);
        block_spreads[t] = medianOf(in_block);
      }
    }
    std::vector<float> offsets, spreads;
    for (std::size_t t = 0; t < block_offsets.size(); ++t)
      if (!std::isnan(block_offsets[t])) {
        offsets.push_back(block_offsets[t]);
        spreads.push_back(block_spreads[t]);
      }
    result.moved = offsets.size() >= 4 && medianOf(offsets) > medianOf(spreads);
    if (result.moved)
      return result;
  }
  if (!sigma_b)
    return result;
  // The median of |along| / sigma_b over the pixels where both are usable (-1 elsewhere).
  std::vector<float> ratios(n);
  {
    const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::ptrdiff_t i = 0; i < size; ++i)
      ratios[i] = !std::isnan(along[i]) && sigma_b[i] > 0.0f ? std::fabs(along[i]) / sigma_b[i] : -1.0f;
  }
  std::size_t count = 0;
  const float median = detail::medianOfNonNegative(ratios.data(), nullptr, n, threads, &count);
  if (count >= 64)
    result.ratio = 1.4826f * 0.70710678f * median;
  return result;
}

FrameOffset
analyseFrameChange(const Grid& a, const Grid& b, const Viewpoint& viewpoint)
{
  return detail::analyseFrameChange(a, b, viewpoint, 1);
}

FrameOffset
detail::analyseFrameChange(const Grid& a, const Grid& b, const Viewpoint& viewpoint, int threads)
{
  FrameOffset result;
  if (a.size() != b.size() || a.width <= 0 || a.height <= 0)
    return result;
  const int width = a.width, height = a.height;
  const std::size_t n = a.size();
  std::vector<float> rho_a(n), rho_b(n);
  (void)threads;
#pragma omp parallel for schedule(static) num_threads(detail::resolveThreads(threads))
  for (std::size_t i = 0; i < n; ++i) {
    const auto range = [&](const Grid& g) {
      const float dx = g.x[i] - viewpoint[0], dy = g.y[i] - viewpoint[1], dz = g.z[i] - viewpoint[2];
      return std::sqrt(dx * dx + dy * dy + dz * dz);
    };
    rho_a[i] = a.valid[i] ? range(a) : 0.0f;
    rho_b[i] = b.valid[i] ? range(b) : 0.0f;
  }
  // The blocks of framesMoved. Per block: the median difference and its spread, and whether the
  // block is structured and shows a shift (see the header).
  const int block = std::max(8, width / 20);
  const int columns = width / block, rows = height / block;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> medians(static_cast<std::size_t>(columns) * rows, nan), spreads(medians);
  std::vector<unsigned char> structured(medians.size(), 0), shifted(medians.size(), 0);
  static const int kShifts[9][2] = {{0, 0}, {1, 0}, {-1, 0}, {0, 1}, {0, -1}, {2, 0}, {-2, 0}, {0, 2}, {0, -2}};
  // The differences of block t against `b` shifted by kShifts[s] into `diff`, every `step`-th
  // pixel along rows and columns; false if fewer than half of those are valid in both.
  const auto differences = [&](int t, int s, int step, std::vector<float>& diff) {
    const int v0 = (t / columns) * block, u0 = (t % columns) * block;
    diff.clear();
    for (int v = v0; v < v0 + block; v += step) {
      const int vb = v + kShifts[s][1];
      if (vb < 0 || vb >= height)
        continue;
      for (int u = u0; u < u0 + block; u += step) {
        const int ub = u + kShifts[s][0];
        if (ub < 0 || ub >= width)
          continue;
        const std::size_t i = static_cast<std::size_t>(v) * width + u, j = static_cast<std::size_t>(vb) * width + ub;
        if (a.valid[i] && b.valid[j])
          diff.push_back(rho_b[j] - rho_a[i]);
      }
    }
    const int side = (block + step - 1) / step;
    return diff.size() >= static_cast<std::size_t>(side * side / 2);
  };
  const auto meanDeviation = [](const std::vector<float>& diff) {
    double sum = 0.0, absolute = 0.0;
    for (float d : diff)
      sum += d;
    const double mean = sum / static_cast<double>(diff.size());
    for (float d : diff)
      absolute += std::fabs(d - mean);
    return absolute / static_cast<double>(diff.size());
  };
  // Each block by one thread into its own slots; a median does not depend on the order of its
  // values. Every other pixel along rows and columns (a quarter of them is plenty for a median
  // and its spread).
#pragma omp parallel num_threads(detail::resolveThreads(threads))
  {
    std::vector<float> diff;
#pragma omp for schedule(dynamic, 4)
    for (int t = 0; t < columns * rows; ++t) {
      if (!differences(t, 0, 2, diff))
        continue;
      const float m = medianOf(diff);
      for (float& d : diff)
        d = std::fabs(d - m);
      medians[t] = m;
      spreads[t] = medianOf(diff);
    }
  }
  std::vector<float> offsets, block_spreads;
  for (std::size_t t = 0; t < medians.size(); ++t)
    if (!std::isnan(medians[t])) {
      offsets.push_back(std::fabs(medians[t]));
      block_spreads.push_back(spreads[t]);
    }
  if (offsets.size() < 4 || !(medianOf(offsets) > medianOf(block_spreads)))
    return result;
  // Too few blocks to tell a smooth drift (a quadratic: 6 coefficients) from blocks that moved
  // against each other: motion, as if there were no drift.
  if (offsets.size() < 24) {
    result.change = FrameChange::motion;
    return result;
  }
  // A quadratic in the image coordinates (scaled to [-1, 1]) fitted to the blocks' medians,
  // weighted by 1 / spread^2 and, against outliers (a block on an object that moved), Huber
  // weights at 2 spreads from the fit, three reweightings. One block's median holds its noise
  // (under correlated noise, a few blobs' worth); the fit over the frame does not.
  struct Sample
  {
    double x, y, m, spread;
  };
  std::vector<Sample> samples;
  for (std::size_t t = 0; t < medians.size(); ++t)
    if (!std::isnan(medians[t])) {
      const int c = static_cast<int>(t) % columns, r = static_cast<int>(t) / columns;
      samples.push_back(Sample{2.0 * ((c + 0.5) * block) / width - 1.0, 2.0 * ((r + 0.5) * block) / height - 1.0,
                               medians[t], std::max(static_cast<double>(spreads[t]), 1e-6)});
    }
  const auto basis = [](double x, double y) {
    Eigen::Matrix<double, 6, 1> b;
    b << 1.0, x, y, x * x, x * y, y * y;
    return b;
  };
  Eigen::Matrix<double, 6, 1> coefficients = Eigen::Matrix<double, 6, 1>::Zero();
  for (int pass = 0; pass < 4; ++pass) {
    Eigen::Matrix<double, 6, 6> normal = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
    for (const Sample& q : samples) {
      const Eigen::Matrix<double, 6, 1> b = basis(q.x, q.y);
      double w = 1.0 / (q.spread * q.spread);
      if (pass > 0) {
        const double r = std::fabs(q.m - coefficients.dot(b));
        w *= std::min(1.0, 2.0 * q.spread / std::max(r, 1e-12));
      }
      normal += w * b * b.transpose();
      rhs += w * q.m * b;
    }
    // A small ridge keeps the fit defined when the blocks line up (e.g. one row of them).
    normal.diagonal().array() += 1e-9 * std::max(normal.trace(), 1e-30);
    coefficients = normal.ldlt().solve(rhs);
  }
  // A drift is smooth: if the fit leaves the blocks' medians farther from it than their spread
  // (what `none` allows), whole blocks moved against each other, which is motion.
  std::vector<float> residuals;
  for (const Sample& q : samples)
    residuals.push_back(static_cast<float>(std::fabs(q.m - coefficients.dot(basis(q.x, q.y)))));
  if (!(medianOf(residuals) <= medianOf(block_spreads))) {
    result.change = FrameChange::motion;
    return result;
  }
  // Smooth: did the image's structure move? Each block against `b` as it is and shifted.
#pragma omp parallel num_threads(detail::resolveThreads(threads))
  {
    std::vector<float> diff;
#pragma omp for schedule(dynamic, 4)
    for (int t = 0; t < columns * rows; ++t) {
      if (std::isnan(medians[t]) || !differences(t, 0, 2, diff))
        continue;
      const double still = meanDeviation(diff);
      double largest = 0.0, smallest = std::numeric_limits<double>::infinity();
      for (int s = 1; s < 9; ++s)
        if (differences(t, s, 2, diff)) {
          const double deviation = meanDeviation(diff);
          largest = std::max(largest, deviation);
          smallest = std::min(smallest, deviation);
        }
      structured[t] = largest > 1.5 * still;
      shifted[t] = structured[t] && smallest < 0.8 * still;
    }
  }
  const int structured_blocks = std::count(structured.begin(), structured.end(), 1);
  const int shifted_blocks = std::count(shifted.begin(), shifted.end(), 1);
  if (structured_blocks >= 8 && 4 * shifted_blocks >= structured_blocks) {
    result.change = FrameChange::motion;
    return result;
  }
  result.change = FrameChange::offset;
  const Eigen::Matrix<float, 6, 1> c = coefficients.cast<float>();
  result.range_offset.resize(n);
  float* __restrict out = result.range_offset.data();
#pragma omp parallel for schedule(static) num_threads(detail::resolveThreads(threads))
  for (int v = 0; v < height; ++v) {
    const float y = 2.0f * (v + 0.5f) / height - 1.0f;
    for (int u = 0; u < width; ++u) {
      const float x = 2.0f * (u + 0.5f) / width - 1.0f;
      out[static_cast<std::size_t>(v) * width + u] = c[0] + c[1] * x + c[2] * y + c[3] * x * x + c[4] * x * y + c[5] * y * y;
    }
  }
  return result;
}

float
estimateTemporalNoiseRatio(const Grid& a, const NormalField& normals_a, const Grid& b, const NoiseProfile& profile_b,
                           const Viewpoint& viewpoint)
{
  return detail::estimateTemporalNoiseRatio(a, normals_a, b, profile_b, viewpoint, 1);
}

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

float
detail::estimateTemporalNoiseRatio(const Grid& a, const NormalField& normals_a, const Grid& b,
                                   const NoiseProfile& profile_b, const Viewpoint& viewpoint, int threads)
{
  if (a.size() != b.size() || normals_a.size() != a.size() || profile_b.empty())
    return 0.0f;
  // sigmaAt(rho_a) of every point (0 where a is invalid), by the vectorized interpolation.
  const std::size_t n = a.size();
  std::vector<float> rho(n), sigma(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float dx = a.x[i] - viewpoint[0], dy = a.y[i] - viewpoint[1], dz = a.z[i] - viewpoint[2];
    rho[i] = a.valid[i] ? std::sqrt(dx * dx + dy * dy + dz * dz) : 0.0f;
  }
  detail::interpolateProfile(profile_b.range, profile_b.sigma, rho.data(), sigma.data(), n);
  return detail::compareFrames(a, normals_a, b, sigma.data(), false, threads).ratio;
}

float
detail::robustMean(std::vector<float>& values)
{
  const std::size_t keep = values.size() * 4 / 5;
  if (keep == 0)
    return 0.0f;
  // Non-negative floats order as their bits do: a histogram of bits 30..20 (the exponent and
  // three mantissa bits) finds the bin holding the keep-th smallest value; the values of the
  // bins below it are all kept, and only that bin's values are selected from (std::nth_element
  // over every value took most of the automatic dilation's estimate).
  constexpr int kShift = 20;
  constexpr std::size_t kBins = std::size_t(1) << (31 - kShift);
  const auto bin = [](float f) { return __builtin_bit_cast(std::uint32_t, f) >> kShift; };
  std::vector<std::uint32_t> histogram(kBins, 0u);
  for (float v : values)
    ++histogram[bin(v)];
  std::size_t below = 0, chosen = 0;
  for (; below + histogram[chosen] < keep; ++chosen)
    below += histogram[chosen];
  double sum = 0.0;
  std::size_t in_bin = 0;
  for (float v : values) {
    const std::uint32_t b = bin(v);
    sum += b < chosen ? double(v) : 0.0;
    if (b == chosen)
      values[in_bin++] = v; // in place: every value is read before its slot can be written
  }
  const std::size_t take = keep - below; // 1 ... in_bin
  std::nth_element(values.begin(), values.begin() + (take - 1), values.begin() + in_bin);
  for (std::size_t i = 0; i < take; ++i)
    sum += values[i];
  return static_cast<float>(sum / keep);
}

NoiseCorrelation
estimateNoiseCorrelation(const Grid& grid, int step)
{
  return detail::estimateNoiseCorrelation(grid, step, 1);
}

NoiseCorrelation
detail::estimateNoiseCorrelation(const Grid& grid, int step, int threads)
{
  NoiseCorrelation result;
  const int w = grid.width, h = grid.height;
  step = std::max(1, step);
  // The lags are independent: one per thread at a time, each with its own values.
  (void)threads;
#pragma omp parallel for schedule(dynamic, 1) num_threads(detail::resolveThreads(threads))
  for (int lag = 1; lag <= 8; ++lag) {
    std::vector<float> values, relative;
    const std::size_t most = 2 * static_cast<std::size_t>(w / step + 1) * static_cast<std::size_t>(h / step + 1);
    values.reserve(most);
    relative.reserve(most);
    // `lateral` is x (along rows) or y (along columns): its ratio to z is the ray's direction, so
    // the centre's pixel footprint is z_c times the angle between the outer rays over 2 lag.
    auto add = [&](std::size_t a, std::size_t c, std::size_t b, const std::vector<float>& lateral) {
      if (!(grid.valid[a] && grid.valid[b] && grid.valid[c]))
        return;
      const float za = grid.z[a], zb = grid.z[b], zc = grid.z[c];
      if (!(za > 0.0f && zb > 0.0f && zc > 0.0f))
        return;
      const float d2 = 1.0f / za - 2.0f / zc + 1.0f / zb;
      const float value = std::fabs(d2) * zc * zc;
      values.push_back(value);
      const float footprint = std::fabs(lateral[b] / zb - lateral[a] / za) * zc / (2.0f * lag);
      if (footprint > 0.0f)
        relative.push_back(value / footprint);
    };
    for (int v = 0; v < h; v += step)
      for (int u = lag; u + lag < w; u += step) {
        const std::size_t c = static_cast<std::size_t>(v) * w + u;
        add(c - lag, c, c + lag, grid.x);
      }
    for (int v = lag; v + lag < h; v += step)
      for (int u = 0; u < w; u += step) {
        const std::size_t c = static_cast<std::size_t>(v) * w + u;
        add(c - static_cast<std::size_t>(lag) * w, c, c + static_cast<std::size_t>(lag) * w, grid.y);
      }
    if (lag == 1)
      result.samples = values.size();
    if (relative.size() >= 64)
      result.scale_in_footprints[lag - 1] = detail::robustMean(relative);
    if (values.size() < 64)
      continue; // scale stays 0
    result.scale[lag - 1] = detail::robustMean(values);
  }
  return result;
}

} // namespace range_nlm
