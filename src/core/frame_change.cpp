// Changes between frames (docs/method.md, "Cross-frame bandwidths"): the motion test, the
// frame-to-frame noise ratio, and the analysis that tells noise, a drift along the rays and
// motion apart (analyseFrameChange: block statistics, a smooth-offset fit, a structure test).
#include "internal.h"
#include "robust_statistics.h"
#include "tuned.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

namespace range_nlm
{

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
    const int block = std::max(tuned::kMotionMinBlockSize, width / tuned::kMotionBlocksAcross);
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
        const float m = medianInPlace(in_block);
        for (float& d : in_block)
          d = std::fabs(d - m);
        block_offsets[t] = std::fabs(m);
        block_spreads[t] = medianInPlace(in_block);
      }
    }
    std::vector<float> offsets, spreads;
    for (std::size_t t = 0; t < block_offsets.size(); ++t)
      if (!std::isnan(block_offsets[t])) {
        offsets.push_back(block_offsets[t]);
        spreads.push_back(block_spreads[t]);
      }
    result.moved = offsets.size() >= tuned::kMotionMinBlocks && medianOf(offsets) > medianOf(spreads);
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
  if (count >= tuned::kNoiseRatioMinPixels)
    result.ratio = 1.4826f * 0.70710678f * median;
  return result;
}

FrameOffset
analyseFrameChange(const Grid& a, const Grid& b, const Viewpoint& viewpoint)
{
  return detail::analyseFrameChange(a, b, viewpoint, 1);
}

namespace
{
/// The blocks of analyseFrameChange over the ranges of two frames of one size: the blocks of
/// framesMoved, `columns` x `rows` of `block` x `block` pixels, block t at column t % columns and
/// row t / columns.
struct ChangeBlocks
{
  const Grid& a;
  const Grid& b;
  const std::vector<float>& rho_a;
  const std::vector<float>& rho_b;
  int width, height;
  int block, columns, rows;
};

/// The shifts of `b` the structure test compares each block with: none, then one and two pixels
/// along a row or a column.
constexpr int kShifts[9][2] = {{0, 0}, {1, 0}, {-1, 0}, {0, 1}, {0, -1}, {2, 0}, {-2, 0}, {0, 2}, {0, -2}};

/// The differences of block t against `b` shifted by kShifts[s] into `diff`, every `step`-th
/// pixel along rows and columns; false if fewer than half of those are valid in both.
bool
differences(const ChangeBlocks& blocks, int t, int s, int step, std::vector<float>& diff)
{
  const int block = blocks.block, columns = blocks.columns, width = blocks.width, height = blocks.height;
  const int v0 = (t / columns) * block, u0 = (t % columns) * block;
  const int sx = kShifts[s][0], sy = kShifts[s][1];
  // The pixels of the block whose shifted pixel lies in the frame, in the order of the lattice.
  int u_first = u0;
  while (u_first + sx < 0)
    u_first += step;
  const int u_end = std::min(u0 + block, width - sx);
  const int side = (block + step - 1) / step;
  diff.resize(static_cast<std::size_t>(side) * side);
  float* out = diff.data();
  std::size_t kept = 0;
  const unsigned char* __restrict va = blocks.a.valid.data();
  const unsigned char* __restrict vb = blocks.b.valid.data();
  const float* __restrict ra = blocks.rho_a.data();
  const float* __restrict rb = blocks.rho_b.data();
  for (int v = v0; v < v0 + block; v += step) {
    const int vb_row = v + sy;
    if (vb_row < 0 || vb_row >= height)
      continue;
    const std::size_t row = static_cast<std::size_t>(v) * width;
    const std::ptrdiff_t shift = static_cast<std::ptrdiff_t>(sy) * width + sx;
    for (int u = u_first; u < u_end; u += step) {
      const std::size_t i = row + u;
      const std::size_t j = static_cast<std::size_t>(static_cast<std::ptrdiff_t>(i) + shift);
      out[kept] = rb[j] - ra[i];
      kept += (va[i] & vb[j]) != 0;
    }
  }
  diff.resize(kept);
  return kept >= static_cast<std::size_t>(side * side / 2);
}

/// The mean absolute deviation of `diff` (not empty) from its mean. Four partial sums in double
/// (exact for these floats but for the rounding of a deviation's last bit), so that the adds do
/// not wait on each other.
double
meanDeviation(const std::vector<float>& diff)
{
  const std::size_t n = diff.size();
  double sum[4] = {0.0, 0.0, 0.0, 0.0}, absolute[4] = {0.0, 0.0, 0.0, 0.0};
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4)
    for (int k = 0; k < 4; ++k)
      sum[k] += diff[i + k];
  for (; i < n; ++i)
    sum[0] += diff[i];
  const double mean = ((sum[0] + sum[1]) + (sum[2] + sum[3])) / static_cast<double>(n);
  for (i = 0; i + 4 <= n; i += 4)
    for (int k = 0; k < 4; ++k)
      absolute[k] += std::fabs(diff[i + k] - mean);
  for (; i < n; ++i)
    absolute[0] += std::fabs(diff[i] - mean);
  return ((absolute[0] + absolute[1]) + (absolute[2] + absolute[3])) / static_cast<double>(n);
}

/// Per block: the median range difference and its spread (the median distance from it), and the
/// mean absolute deviation of the differences (the structure test's deviation without a shift);
/// NaN where too few pixels are valid in both frames.
struct BlockStatistics
{
  std::vector<float> medians, spreads;
  std::vector<double> deviations;
};

/// BlockStatistics of every block. Each block by one thread into its own slots; a median does not
/// depend on the order of its values. Every other pixel along rows and columns (a quarter of them
/// is plenty for a median and its spread).
BlockStatistics
blockStatistics(const ChangeBlocks& blocks, int threads)
{
  const int columns = blocks.columns, rows = blocks.rows;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  BlockStatistics stats;
  stats.medians.assign(static_cast<std::size_t>(columns) * rows, nan);
  stats.spreads = stats.medians;
  stats.deviations.assign(stats.medians.size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<float>& medians = stats.medians;
  std::vector<float>& spreads = stats.spreads;
  std::vector<double>& deviations = stats.deviations;
  (void)threads;
#pragma omp parallel num_threads(detail::resolveThreads(threads))
  {
    std::vector<float> diff;
#pragma omp for schedule(dynamic, 4)
    for (int t = 0; t < columns * rows; ++t) {
      if (!differences(blocks, t, 0, 2, diff))
        continue;
      deviations[t] = meanDeviation(diff); // (in the order taken, before the medians reorder them)
      const float m = detail::medianInPlace(diff);
      for (float& d : diff)
        d = std::fabs(d - m);
      medians[t] = m;
      spreads[t] = detail::medianInPlace(diff);
    }
  }
  return stats;
}

/// A block's median at its centre in image coordinates scaled to [-1, 1], with its spread.
struct BlockSample
{
  double x, y, m, spread;
};

/// The BlockSample of every block with a median, in block order.
std::vector<BlockSample>
blockSamples(const ChangeBlocks& blocks, const BlockStatistics& stats)
{
  const int columns = blocks.columns, block = blocks.block, width = blocks.width, height = blocks.height;
  const std::vector<float>& medians = stats.medians;
  const std::vector<float>& spreads = stats.spreads;
  std::vector<BlockSample> samples;
  for (std::size_t t = 0; t < medians.size(); ++t)
    if (!std::isnan(medians[t])) {
      const int c = static_cast<int>(t) % columns, r = static_cast<int>(t) / columns;
      samples.push_back(BlockSample{2.0 * ((c + 0.5) * block) / width - 1.0,
                                    2.0 * ((r + 0.5) * block) / height - 1.0, medians[t],
                                    std::max(static_cast<double>(spreads[t]), 1e-6)});
    }
  return samples;
}

/// The coefficients of the quadratic 1, x, y, x^2, xy, y^2.
using Quadratic = Eigen::Matrix<double, 6, 1>;

/// The quadratic's basis at (x, y).
Quadratic
quadraticBasis(double x, double y)
{
  Quadratic b;
  b << 1.0, x, y, x * x, x * y, y * y;
  return b;
}

/// The quadratic fitted to the blocks' medians, weighted by 1 / spread^2 and, against outliers (a
/// block on an object that moved), Huber weights at kDriftHuberSpreads spreads from the fit, three
/// reweightings. One block's median holds its noise (under correlated noise, a few blobs' worth);
/// the fit over the frame does not.
Quadratic
fitSmoothOffset(const std::vector<BlockSample>& samples)
{
  Quadratic coefficients = Quadratic::Zero();
  for (int pass = 0; pass < 4; ++pass) {
    Eigen::Matrix<double, 6, 6> normal = Eigen::Matrix<double, 6, 6>::Zero();
    Quadratic rhs = Quadratic::Zero();
    for (const BlockSample& q : samples) {
      const Quadratic b = quadraticBasis(q.x, q.y);
      double w = 1.0 / (q.spread * q.spread);
      if (pass > 0) {
        const double r = std::fabs(q.m - coefficients.dot(b));
        w *= std::min(1.0, tuned::kDriftHuberSpreads * q.spread / std::max(r, 1e-12));
      }
      normal += w * b * b.transpose();
      rhs += w * q.m * b;
    }
    // A small ridge keeps the fit defined when the blocks line up (e.g. one row of them).
    normal.diagonal().array() += 1e-9 * std::max(normal.trace(), 1e-30);
    coefficients = normal.ldlt().solve(rhs);
  }
  return coefficients;
}

/// Whether the fit explains the blocks' medians: a drift is smooth, so if the fit leaves them
/// farther from it than their spread (what `none` allows), whole blocks moved against each other,
/// which is motion.
bool
fitIsSmooth(const std::vector<BlockSample>& samples, const Quadratic& coefficients,
            const std::vector<float>& block_spreads)
{
  std::vector<float> residuals;
  for (const BlockSample& q : samples)
    residuals.push_back(static_cast<float>(std::fabs(q.m - coefficients.dot(quadraticBasis(q.x, q.y)))));
  return detail::medianOf(residuals) <= detail::medianOf(block_spreads);
}

/// Whether the image's structure moved: each block with a median against `b` as it is and
/// shifted by kShifts. A block is structured if a shift makes the mean absolute deviation of its
/// differences kStructuredDeviation times larger, and shows a shift if one makes it
/// kShiftedDeviation times smaller than no shift; the structure moved if at least
/// kMinStructuredBlocks are structured and one in kStructuredPerShifted of them shows a shift.
bool
structureMoved(const ChangeBlocks& blocks, const BlockStatistics& stats, int threads)
{
  const int columns = blocks.columns, rows = blocks.rows;
  const std::vector<float>& medians = stats.medians;
  std::vector<unsigned char> structured(medians.size(), 0), shifted(medians.size(), 0);
  (void)threads;
#pragma omp parallel num_threads(detail::resolveThreads(threads))
  {
    std::vector<float> diff;
#pragma omp for schedule(dynamic, 4)
    for (int t = 0; t < columns * rows; ++t) {
      if (std::isnan(medians[t]))
        continue;
      const double still = stats.deviations[t];
      double largest = 0.0, smallest = std::numeric_limits<double>::infinity();
      for (int s = 1; s < 9; ++s)
        if (differences(blocks, t, s, 2, diff)) {
          const double deviation = meanDeviation(diff);
          largest = std::max(largest, deviation);
          smallest = std::min(smallest, deviation);
        }
      structured[t] = largest > tuned::kStructuredDeviation * still;
      shifted[t] = structured[t] && smallest < tuned::kShiftedDeviation * still;
    }
  }
  const int structured_blocks = std::count(structured.begin(), structured.end(), 1);
  const int shifted_blocks = std::count(shifted.begin(), shifted.end(), 1);
  return structured_blocks >= tuned::kMinStructuredBlocks &&
         tuned::kStructuredPerShifted * shifted_blocks >= structured_blocks;
}

/// The quadratic at every pixel of a width x height frame into `out`.
void
evaluateOffsetField(const Quadratic& coefficients, int width, int height, int threads, float* __restrict out)
{
  const Eigen::Matrix<float, 6, 1> c = coefficients.cast<float>();
  (void)threads;
#pragma omp parallel for schedule(static) num_threads(detail::resolveThreads(threads))
  for (int v = 0; v < height; ++v) {
    const float y = 2.0f * (v + 0.5f) / height - 1.0f;
    for (int u = 0; u < width; ++u) {
      const float x = 2.0f * (u + 0.5f) / width - 1.0f;
      out[static_cast<std::size_t>(v) * width + u] = c[0] + c[1] * x + c[2] * y + c[3] * x * x + c[4] * x * y + c[5] * y * y;
    }
  }
}
} // namespace

FrameOffset
detail::analyseFrameChange(const Grid& a, const Grid& b, const Viewpoint& viewpoint, int threads)
{
  std::vector<float> rho_a, rho_b;
  return analyseFrameChange(a, b, viewpoint, threads, rho_a, rho_b);
}

FrameOffset
detail::analyseFrameChange(const Grid& a, const Grid& b, const Viewpoint& viewpoint, int threads,
                           std::vector<float>& rho_a, std::vector<float>& rho_b)
{
  FrameOffset result;
  if (a.size() != b.size() || a.width <= 0 || a.height <= 0)
    return result;
  const int width = a.width, height = a.height;
  detail::rangesOf(a, viewpoint, detail::resolveThreads(threads), rho_a);
  detail::rangesOf(b, viewpoint, detail::resolveThreads(threads), rho_b);
  // The blocks of framesMoved. Per block: the median difference and its spread, and whether the
  // block is structured and shows a shift (see the header).
  const int block = std::max(tuned::kMotionMinBlockSize, width / tuned::kMotionBlocksAcross);
  const ChangeBlocks blocks{a, b, rho_a, rho_b, width, height, block, width / block, height / block};
  const BlockStatistics stats = blockStatistics(blocks, threads);
  std::vector<float> offsets, block_spreads;
  for (std::size_t t = 0; t < stats.medians.size(); ++t)
    if (!std::isnan(stats.medians[t])) {
      offsets.push_back(std::fabs(stats.medians[t]));
      block_spreads.push_back(stats.spreads[t]);
    }
  if (offsets.size() < tuned::kMotionMinBlocks || !(medianOf(offsets) > medianOf(block_spreads)))
    return result;
  // Too few blocks to tell a smooth drift (a quadratic: 6 coefficients) from blocks that moved
  // against each other: motion, as if there were no drift.
  if (offsets.size() < tuned::kDriftMinBlocks) {
    result.change = FrameChange::motion;
    return result;
  }
  // A quadratic in the image coordinates (scaled to [-1, 1]) fitted to the blocks' medians.
  const std::vector<BlockSample> samples = blockSamples(blocks, stats);
  const Quadratic coefficients = fitSmoothOffset(samples);
  if (!fitIsSmooth(samples, coefficients, block_spreads)) {
    result.change = FrameChange::motion;
    return result;
  }
  // Smooth: did the image's structure move? Each block against `b` as it is and shifted.
  if (structureMoved(blocks, stats, threads)) {
    result.change = FrameChange::motion;
    return result;
  }
  result.change = FrameChange::offset;
  result.range_offset.resize(a.size());
  evaluateOffsetField(coefficients, width, height, threads, result.range_offset.data());
  return result;
}

float
estimateTemporalNoiseRatio(const Grid& a, const NormalField& normals_a, const Grid& b, const NoiseProfile& profile_b,
                           const Viewpoint& viewpoint)
{
  return detail::estimateTemporalNoiseRatio(a, normals_a, b, profile_b, viewpoint, 1);
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

} // namespace range_nlm
