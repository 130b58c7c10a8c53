// The range-adaptive noise profile (docs/method.md, "Automatic bandwidths"): the noise sigma and
// the window extent of sampled windows, binned by range, and their interpolation at any range.
#include "internal.h"
#include "robust_statistics.h"
#include "simd/kernels.h"
#include "tuned.h"

#include <pcl/common/eigen.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>

namespace range_nlm
{
namespace
{
/// The profile (xs, ys) at x: linear between its ranges, constant beyond its ends; 0 if empty.
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

/// detail::interpolateProfile, with the second profile (ys2, out2) if Second (then both non-null).
/// Compiled once per instruction set below (the same operations, this file being compiled without
/// contraction into fused multiply-adds, so every build gives the same bits).
template <bool Second>
[[gnu::always_inline]] inline void
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

using InterpolateBuild = void (*)(const std::vector<float>&, const std::vector<float>&, const float*, float*,
                                  std::size_t, const std::vector<float>*, float*);

template <bool Second>
void
interpolateBaseline(const std::vector<float>& xs, const std::vector<float>& ys, const float* x, float* out,
                    std::size_t n, const std::vector<float>* ys2, float* out2)
{
  interpolateProfiles<Second>(xs, ys, x, out, n, ys2, out2);
}

#if defined(__x86_64__)
template <bool Second>
[[RANGE_NLM_TARGET_AVX2]] void
interpolateAvx2(const std::vector<float>& xs, const std::vector<float>& ys, const float* x, float* out,
                std::size_t n, const std::vector<float>* ys2, float* out2)
{
  interpolateProfiles<Second>(xs, ys, x, out, n, ys2, out2);
}

template <bool Second>
[[RANGE_NLM_TARGET_AVX512]] void
interpolateAvx512(const std::vector<float>& xs, const std::vector<float>& ys, const float* x, float* out,
                  std::size_t n, const std::vector<float>* ys2, float* out2)
{
  interpolateProfiles<Second>(xs, ys, x, out, n, ys2, out2);
}
#endif

/// The builds of the interpolation (one profile, two profiles) this CPU runs, slowest first.
std::vector<std::pair<InterpolateBuild, InterpolateBuild>>
interpolateBuilds()
{
  std::vector<std::pair<InterpolateBuild, InterpolateBuild>> all{
      {&interpolateBaseline<false>, &interpolateBaseline<true>}};
#if defined(__x86_64__)
  if (detail::cpuRunsAvx2())
    all.emplace_back(&interpolateAvx2<false>, &interpolateAvx2<true>);
  if (detail::cpuRunsAvx512())
    all.emplace_back(&interpolateAvx512<false>, &interpolateAvx512<true>);
#endif
  return all;
}

/// The fastest build: the one-profile form, or the two-profile form if `second`.
InterpolateBuild
fastestInterpolate(bool second)
{
  static const std::pair<InterpolateBuild, InterpolateBuild> fastest = interpolateBuilds().back();
  return second ? fastest.second : fastest.first;
}

/// `samples` pixels of an n-pixel frame drawn with replacement from those for which eligible(i)
/// holds, in the order drawn: the eligible pixels of ranks rng() % eligible count (rng seeded
/// with `seed`), a rank found by a prefix count per chunk of 64 pixels. `count` receives the
/// number of eligible pixels; none is drawn when it is 0.
template <typename Eligible>
std::vector<int>
drawSamples(std::size_t n, const Eligible& eligible, int samples, std::uint64_t seed, std::uint64_t& count)
{
  constexpr std::size_t kChunk = 64;
  const std::size_t chunks = (n + kChunk - 1) / kChunk;
  std::vector<std::uint64_t> before(chunks + 1, 0u); // eligible pixels before each chunk
  for (std::size_t c = 0; c < chunks; ++c) {
    const std::size_t end = std::min(n, (c + 1) * kChunk);
    std::uint64_t in_chunk = 0;
    for (std::size_t i = c * kChunk; i < end; ++i)
      in_chunk += eligible(i) ? 1u : 0u;
    before[c + 1] = before[c] + in_chunk;
  }
  count = before[chunks];
  std::vector<int> picked;
  if (count == 0 || samples <= 0)
    return picked;
  std::mt19937_64 rng(seed);
  picked.resize(static_cast<std::size_t>(samples));
  for (int& k : picked) {
    const std::uint64_t rank = rng() % count;
    const std::size_t c =
        static_cast<std::size_t>(std::upper_bound(before.begin(), before.end(), rank) - before.begin()) - 1;
    std::uint64_t left = rank - before[c];
    std::size_t i = c * kChunk;
    for (;; ++i)
      if (eligible(i) && left-- == 0)
        break;
    k = static_cast<int>(i);
  }
  return picked;
}

/// The bins of a profile over `count` samples sorted by range: equal counts, tuned::kProfileSamplesPerBin
/// each, 1 to tuned::kProfileMaxBins; per_bin(lo, hi) for each bin's samples [lo, hi), in range order.
template <typename PerBin>
void
forEachProfileBin(std::size_t count, const PerBin& per_bin)
{
  const std::size_t bins = std::clamp<std::size_t>(count / tuned::kProfileSamplesPerBin, 1, tuned::kProfileMaxBins);
  for (std::size_t b = 0; b < bins; ++b)
    per_bin(b * count / bins, (b + 1) * count / bins);
}

/// The median of one field of samples [lo, hi).
template <typename Sample>
float
medianOfField(const std::vector<Sample>& samples, std::size_t lo, std::size_t hi, float Sample::*field)
{
  std::vector<float> values;
  values.reserve(hi - lo);
  for (std::size_t i = lo; i < hi; ++i)
    values.push_back(samples[i].*field);
  return detail::medianOf(values);
}

/// evaluate(k, sample) at every picked pixel k by `threads` threads, each into a slot of its own;
/// the samples for which it returned true, in the order picked (whatever the threads).
template <typename Sample, typename Evaluate>
std::vector<Sample>
evaluateSamples(const std::vector<int>& picked, int threads, const Evaluate& evaluate)
{
  const int samples = static_cast<int>(picked.size());
  std::vector<Sample> slots(picked.size());
  std::vector<unsigned char> kept(picked.size(), 0);
  (void)threads;
#pragma omp parallel for schedule(dynamic, 16) num_threads(detail::resolveThreads(threads))
  for (int s = 0; s < samples; ++s)
    kept[s] = evaluate(picked[s], slots[s]) ? 1 : 0;
  std::vector<Sample> found;
  found.reserve(slots.size());
  for (std::size_t s = 0; s < slots.size(); ++s)
    if (kept[s])
      found.push_back(slots[s]);
  return found;
}

/// The range of pixel k's point from the viewpoint, in double.
double
rangeOfPoint(const Grid& grid, int k, const Viewpoint& viewpoint)
{
  const double dx = grid.x[k] - viewpoint[0], dy = grid.y[k] - viewpoint[1], dz = grid.z[k] - viewpoint[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

/// The bins' ranges made strictly increasing: equal ranges (e.g. a fronto-parallel plane) would
/// make interpolation degenerate.
void
strictlyIncreasing(std::vector<float>& range)
{
  for (std::size_t b = 1; b < range.size(); ++b)
    range[b] = std::max(range[b], std::nextafter(range[b - 1], 1e30f));
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
    fastestInterpolate(true)(xs, ys, x, out, n, ys2, out2);
  else
    fastestInterpolate(false)(xs, ys, x, out, n, nullptr, nullptr);
}

std::size_t
detail::interpolateProfileBuilds()
{
  return interpolateBuilds().size();
}

void
detail::interpolateProfileWithBuild(std::size_t build, const std::vector<float>& xs, const std::vector<float>& ys,
                                    const float* x, float* out, std::size_t n, const std::vector<float>* ys2,
                                    float* out2)
{
  const auto chosen = interpolateBuilds().at(build);
  if (xs.empty()) {
    interpolateProfile(xs, ys, x, out, n, ys2, out2);
    return;
  }
  if (ys2 && out2)
    chosen.second(xs, ys, x, out, n, ys2, out2);
  else
    chosen.first(xs, ys, x, out, n, nullptr, nullptr);
}

void
detail::interpolateProfile(const std::vector<float>& xs, const std::vector<float>& ys, const float* x, float* out,
                           std::size_t n, int threads, const std::vector<float>* ys2, float* out2)
{
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(n), block = 4096;
  (void)threads;
#pragma omp parallel for schedule(static) num_threads(detail::resolveThreads(threads))
  for (std::ptrdiff_t lo = 0; lo < size; lo += block)
    interpolateProfile(xs, ys, x + lo, out + lo, static_cast<std::size_t>(std::min(block, size - lo)), ys2,
                       out2 ? out2 + lo : nullptr);
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
  // The samples: valid points drawn at random (drawSamples).
  std::uint64_t valid_count = 0;
  const std::vector<int> picked =
      drawSamples(grid.size(), [&](std::size_t i) { return grid.valid[i] != 0; }, samples, seed, valid_count);
  if (valid_count == 0)
    throw UnfilterableFrame("range_nlm: the cloud has no valid point; nothing to estimate the noise from");
  // At least the 3 x 3 neighbourhood: a plane fit needs 4 points, and a 1 x 1 search window (which
  // moves nothing) must not make the noise estimate impossible.
  const int r = std::max(1, search_window / 2);
  struct Sample
  {
    float rho, sigma, extent;
  };
  // Each sampled window's sigma and extent; windows of too few points are left out.
  const auto evaluate = [&](int k, Sample& sample) {
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
      return false;
    const double inv = 1.0 / count;
    const double mx = sum[0] * inv, my = sum[1] * inv, mz = sum[2] * inv;
    Eigen::Matrix3d cov;
    cov << sq[0] * inv - mx * mx, sq[1] * inv - mx * my, sq[2] * inv - mx * mz, sq[1] * inv - mx * my,
        sq[3] * inv - my * my, sq[4] * inv - my * mz, sq[2] * inv - mx * mz, sq[4] * inv - my * mz,
        sq[5] * inv - mz * mz;
    double smallest = 0.0;
    Eigen::Vector3d normal;
    pcl::eigen33(cov, smallest, normal);
    const double rho = rangeOfPoint(grid, k, viewpoint);
    if (!(rho > 0.0))
      return false;
    sample = Sample{float(rho), float(std::sqrt(std::max(0.0, smallest))), float(std::sqrt(max_dist2) / rho)};
    return true;
  };
  std::vector<Sample> found = evaluateSamples<Sample>(picked, threads, evaluate);
  if (found.empty())
    throw UnfilterableFrame("range_nlm: no sampled window has 4 valid points; cannot estimate the noise");
  std::sort(found.begin(), found.end(), [](const Sample& a, const Sample& b) { return a.rho < b.rho; });
  NoiseProfile profile;
  forEachProfileBin(found.size(), [&](std::size_t lo, std::size_t hi) {
    profile.range.push_back(medianOfField(found, lo, hi, &Sample::rho));
    profile.sigma.push_back(medianOfField(found, lo, hi, &Sample::sigma));
    profile.extent.push_back(medianOfField(found, lo, hi, &Sample::extent));
  });
  strictlyIncreasing(profile.range);
  return profile;
}

void
detail::estimatePatchSpread(const Grid& grid, const NormalField& normals, int search_window, int patch_size,
                            int samples, std::uint64_t seed, const Viewpoint& viewpoint, int threads, float quantile,
                            std::vector<float>& range, std::vector<float>& spread)
{
  range.clear();
  spread.clear();
  const std::size_t n = grid.size();
  const auto candidate = [&](std::size_t i) {
    return grid.valid[i] != 0 && std::isfinite(normals.nx[i]) && std::isfinite(normals.ny[i]) &&
           std::isfinite(normals.nz[i]);
  };
  // The samples: points with a finite normal drawn at random (drawSamples).
  std::uint64_t candidates = 0;
  const std::vector<int> picked = drawSamples(n, candidate, samples, seed, candidates);
  if (picked.empty())
    return;
  const int r = std::max(0, search_window / 2), pr = std::max(0, patch_size / 2);
  const double q = std::clamp(static_cast<double>(quantile), 0.0, 1.0);
  struct Sample
  {
    float rho, sim;
  };
  // Each sampled point's low quantile of Sim to its candidates; points without one are left out.
  const auto evaluate = [&](int k, Sample& sample) {
    const int u = k % grid.width, v = k / grid.width;
    const double nx = normals.nx[k], ny = normals.ny[k], nz = normals.nz[k];
    std::vector<float> sims;
    sims.reserve(static_cast<std::size_t>((2 * r + 1) * (2 * r + 1)));
    for (int jv = std::max(0, v - r); jv <= std::min(grid.height - 1, v + r); ++jv)
      for (int ju = std::max(0, u - r); ju <= std::min(grid.width - 1, u + r); ++ju) {
        const int j = jv * grid.width + ju;
        if (j == k || !grid.valid[j])
          continue;
        double sum = 0.0;
        int pairs = 0;
        for (int ov = -pr; ov <= pr; ++ov)
          for (int ou = -pr; ou <= pr; ++ou) {
            const int av = v + ov, au = u + ou, bv = jv + ov, bu = ju + ou;
            if (av < 0 || av >= grid.height || au < 0 || au >= grid.width || bv < 0 || bv >= grid.height ||
                bu < 0 || bu >= grid.width)
              continue;
            const int a = av * grid.width + au, b = bv * grid.width + bu;
            if (!grid.valid[a] || !grid.valid[b])
              continue;
            const double h = (double(grid.x[a]) - grid.x[b]) * nx + (double(grid.y[a]) - grid.y[b]) * ny +
                             (double(grid.z[a]) - grid.z[b]) * nz;
            sum += h * h;
            ++pairs;
          }
        if (pairs > 0)
          sims.push_back(static_cast<float>(sum / pairs));
      }
    if (sims.empty())
      return false;
    const std::size_t at = std::min(sims.size() - 1, static_cast<std::size_t>(q * double(sims.size() - 1) + 0.5));
    std::nth_element(sims.begin(), sims.begin() + static_cast<std::ptrdiff_t>(at), sims.end());
    const double rho = rangeOfPoint(grid, k, viewpoint);
    if (!(rho > 0.0))
      return false;
    sample = Sample{float(rho), sims[at]};
    return true;
  };
  std::vector<Sample> found = evaluateSamples<Sample>(picked, threads, evaluate);
  if (found.empty())
    return;
  std::stable_sort(found.begin(), found.end(), [](const Sample& a, const Sample& b) { return a.rho < b.rho; });
  forEachProfileBin(found.size(), [&](std::size_t lo, std::size_t hi) {
    range.push_back(medianOfField(found, lo, hi, &Sample::rho));
    spread.push_back(std::sqrt(std::max(0.0f, medianOfField(found, lo, hi, &Sample::sim))));
  });
  strictlyIncreasing(range);
}

} // namespace range_nlm
