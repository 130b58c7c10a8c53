// Orchestration of the kernel: normals, bandwidths, frame weights, offsets and displacement.
#include "kernel_math.h"

#include <range_nlm/kernel.h>

#include <algorithm>
#ifdef _OPENMP
#include <omp.h>
#endif
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace range_nlm
{
namespace detail
{
void
computeOffsetsDirect(const Grid&, const NormalField&, const std::vector<FrameTerm>&, int, int, int,
                     const std::vector<unsigned char>&, std::vector<float>&);
void
computeOffsetsFast(const Grid&, const NormalField&, const std::vector<FrameTerm>&, int, int, int,
                   const std::vector<unsigned char>&, std::vector<float>&);

float
expNonPositive(float x)
{
  return expNonPositiveInline(x);
}

float
inverseSquare(float bandwidth)
{
  return inverseSquareInline(bandwidth);
}
} // namespace detail

void
computeOffsets(const Grid& center, const NormalField& normals, const std::vector<FrameTerm>& frames,
               int search_window, int patch_size, Evaluation evaluation, int threads,
               const std::vector<unsigned char>& active, std::vector<float>& offsets)
{
  for (const FrameTerm& term : frames)
    if (term.grid == nullptr || term.grid->width != center.width || term.grid->height != center.height)
      throw std::invalid_argument("range_nlm: every frame must have the size of the filtered frame");
  if (!active.empty() && active.size() != center.size())
    throw std::invalid_argument("range_nlm: the active mask must have one entry per point");
  offsets.assign(center.size(), 0.0f);
  if (evaluation == Evaluation::direct)
    detail::computeOffsetsDirect(center, normals, frames, search_window, patch_size, threads, active, offsets);
  else
    detail::computeOffsetsFast(center, normals, frames, search_window, patch_size, threads, active, offsets);
}

void
applyOffsets(Grid& grid, const NormalField& normals, const std::vector<float>& offsets,
             Displacement displacement, const Viewpoint& viewpoint)
{
  for (std::size_t i = 0; i < grid.size(); ++i) {
    const float h = offsets[i];
    if (!grid.valid[i] || h == 0.0f || !std::isfinite(h))
      continue;
    const float nx = normals.nx[i], ny = normals.ny[i], nz = normals.nz[i];
    if (displacement == Displacement::normal) {
      grid.x[i] -= h * nx;
      grid.y[i] -= h * ny;
      grid.z[i] -= h * nz;
      continue;
    }
    // Stay on the camera ray and land on the plane (q - p) . n = -h.
    float vx = grid.x[i] - viewpoint[0], vy = grid.y[i] - viewpoint[1], vz = grid.z[i] - viewpoint[2];
    const float len = std::sqrt(vx * vx + vy * vy + vz * vz);
    if (!(len > 0.0f))
      continue;
    vx /= len, vy /= len, vz /= len;
    float c = vx * nx + vy * ny + vz * nz;
    const float min_cos = 0.25f; // at grazing angles the ray step is limited to 4 h
    if (std::fabs(c) < min_cos)
      c = c < 0.0f ? -min_cos : min_cos;
    const float t = -h / c;
    grid.x[i] += t * vx;
    grid.y[i] += t * vy;
    grid.z[i] += t * vz;
  }
}

float
temporalDistanceWeight(int k, int center)
{
  return std::ldexp(1.0f, -std::abs(k - center));
}

float
temporalNoiseWeight(float s_k, float s_max)
{
  if (!(s_max > 0.0f))
    return std::exp(-1.0f); // all frames noise-free: equal weights
  const float ratio = s_k / s_max;
  return std::exp(-ratio * ratio);
}

namespace
{

Bandwidths
finishBandwidths(Bandwidths b, const FilterParameters& p)
{
  b.distance = p.distance_bandwidth > 0.0f ? p.distance_bandwidth : p.distance_scale * b.mu_d;
  b.similarity = p.similarity_bandwidth > 0.0f ? p.similarity_bandwidth : p.similarity_scale * b.sigma_s;
  return b;
}
} // namespace

FilterRun
runFilter(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
          const Viewpoint& viewpoint, const std::vector<unsigned char>& active)
{
  if (frames.empty() || center < 0 || center >= static_cast<int>(frames.size()) || !frames[center])
    throw std::invalid_argument("range_nlm: the current frame index is outside the frame list");
  const Grid& input = *frames[center];
  if (input.width <= 0 || input.height <= 0)
    throw std::invalid_argument("range_nlm: the cloud is empty or not organized (width x height = " +
                                std::to_string(input.width) + " x " + std::to_string(input.height) + ")");
  parameters.validateFor(input.width, input.height);
  for (std::size_t k = 0; k < frames.size(); ++k)
    if (!frames[k] || frames[k]->width != input.width || frames[k]->height != input.height) {
      std::ostringstream msg;
      msg << "range_nlm: frame " << k << " is " << (frames[k] ? frames[k]->width : 0) << " x "
          << (frames[k] ? frames[k]->height : 0) << " but the current frame is " << input.width << " x "
          << input.height;
      throw std::invalid_argument(msg.str());
    }
  if (input.countValid() == 0)
    throw std::invalid_argument("range_nlm: the cloud has no valid point (all NaN); nothing to filter");

  // OpenMP treats num_threads(0) as an error; map 0 to the runtime's default.
  int threads = parameters.threads;
  if (threads == 0) {
#ifdef _OPENMP
    threads = omp_get_max_threads();
#else
    threads = 1;
#endif
  }

  FilterRun run;
  run.output = input;
  const int count = static_cast<int>(frames.size());

  // Bandwidths of the neighbour frames are estimated once, from their own data.
  std::vector<Bandwidths> bandwidths(count);
  std::vector<bool> usable(count, true);
  for (int k = 0; k < count; ++k) {
    if (k == center)
      continue;
    const NormalField nk = estimateNormals(*frames[k], parameters.normal_window, viewpoint, threads);
    try {
      bandwidths[k] = finishBandwidths(
          estimateBandwidths(*frames[k], nk, parameters.search_window, parameters.bandwidth_samples,
                             parameters.seed + static_cast<std::uint64_t>(k - center) * 7919u),
          parameters);
    } catch (const std::invalid_argument&) {
      usable[k] = false; // an all-NaN neighbour contributes nothing
    }
  }

  std::vector<float> offsets;
  for (int iteration = 0; iteration < parameters.iterations; ++iteration) {
    const Grid& current = run.output;
    NormalField normals = estimateNormals(current, parameters.normal_window, viewpoint, threads);
    bandwidths[center] = finishBandwidths(
        estimateBandwidths(current, normals, parameters.search_window, parameters.bandwidth_samples,
                           parameters.seed),
        parameters);
    if (parameters.normal_presmooth_window > 1) {
      const Grid smooth = presmoothAlongRays(current, parameters.normal_presmooth_window,
                                             parameters.normal_presmooth_range * bandwidths[center].sigma_s,
                                             viewpoint, threads);
      normals = estimateNormals(smooth, parameters.normal_window, viewpoint, threads);
    }

    float s_max = 0.0f;
    for (int k = 0; k < count; ++k)
      if (usable[k])
        s_max = std::max(s_max, bandwidths[k].similarity);
    std::vector<FrameTerm> terms;
    std::vector<float> weights(count, 0.0f);
    for (int k = 0; k < count; ++k) {
      if (!usable[k])
        continue;
      weights[k] = temporalDistanceWeight(k, center) * temporalNoiseWeight(bandwidths[k].similarity, s_max);
      terms.push_back(FrameTerm{k == center ? &current : frames[k], bandwidths[k].distance,
                                bandwidths[k].similarity, weights[k]});
    }
    if (iteration == 0) {
      run.bandwidths = bandwidths;
      run.frame_weights = weights;
    }
    computeOffsets(current, normals, terms, parameters.search_window, parameters.patch_size,
                   parameters.evaluation, threads, active, offsets);
    applyOffsets(run.output, normals, offsets, parameters.displacement, viewpoint);
  }
  return run;
}

} // namespace range_nlm
