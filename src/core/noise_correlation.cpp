// The noise correlation of a frame (docs/method.md, "Spatially correlated noise: dilated
// passes"): the robust scale of the second differences of inverse depth over pixel lags, behind
// the automatic dilation.
#include "internal.h"
#include "robust_statistics.h"
#include "tuned.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace range_nlm
{

static_assert(tuned::kNoiseCorrelationLags ==
                  static_cast<int>(std::tuple_size<decltype(NoiseCorrelation::scale)>::value),
              "NoiseCorrelation holds one scale per lag");

NoiseCorrelation
estimateNoiseCorrelation(const Grid& grid, int step)
{
  return detail::estimateNoiseCorrelation(grid, step, 1);
}

int
detail::dilationReferenceLag(int width)
{
  return std::clamp((tuned::kDilationReferenceLag * width + tuned::kDilationReferenceWidth / 2) /
                        tuned::kDilationReferenceWidth,
                    tuned::kDilationMinLag, tuned::kDilationMaxLag);
}

float
noiseCorrelationLength(const NoiseCorrelation& correlation, int width)
{
  const int lag = detail::dilationReferenceLag(width);
  const float near = correlation.scale[0] * correlation.scale[0];
  const float far = correlation.scale[lag - 1] * correlation.scale[lag - 1];
  if (!(far > 0.0f) || !(near < tuned::kCorrelatedVarianceRatio * far))
    return 0.0f;
  // The variance rises from lag 1 towards its plateau; the first lag where it has risen by the
  // factor kCorrelationLengthRise, or reached that fraction of the variance at lag R (where the
  // plateau lies within R and is less than that rise), interpolated linearly between lags.
  const float target = std::min(tuned::kCorrelationLengthRise * near, far / tuned::kCorrelationLengthRise);
  float previous = near;
  for (int l = 2; l <= lag; ++l) {
    const float v = correlation.scale[l - 1] * correlation.scale[l - 1];
    if (v >= target)
      return v > previous ? static_cast<float>(l - 1) + (target - previous) / (v - previous) : static_cast<float>(l);
    previous = v;
  }
  return static_cast<float>(lag);
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
  for (int lag = 1; lag <= tuned::kNoiseCorrelationLags; ++lag) {
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
    if (relative.size() >= tuned::kNoiseCorrelationMinTriples)
      result.scale_in_footprints[lag - 1] = detail::robustMean(relative);
    if (values.size() < tuned::kNoiseCorrelationMinTriples)
      continue; // scale stays 0
    result.scale[lag - 1] = detail::robustMean(values);
  }
  return result;
}

} // namespace range_nlm
