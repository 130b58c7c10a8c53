// The per-point uncertainty (FilterParameters::uncertainty; docs/method.md, "Per-point
// uncertainty"): each pass's weights carried into the standard deviation of every point's height.
#include "stages.h"

#include "../tuned.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace range_nlm
{
namespace detail
{
namespace
{

/// What the noise correlation of a frame says about averaging its points: `area`, the number of
/// pixels whose noise one pixel's noise is correlated with (1 for independent noise), and
/// `residual`, the share of the noise variance a plane fitted over the search window leaves
/// (the noise profile's sigma^2 is that share of the true one).
struct CorrelatedNoise
{
  float area = 1.0f;
  float residual = 1.0f;
};

/// From the second differences of the frame at lags 1 .. R (estimateNoiseCorrelation): their
/// variance at lag l is sigma^2 (6 - 8 rho(l) + 2 rho(2 l)), 6 sigma^2 beyond the correlation
/// length. With rho taken as 0 from lag R on, rho(l) follows from lag R / 2 down. Independent
/// noise (the automatic dilation's test: the variance at lag 1 at least half that at lag R) has
/// area 1 and residual 1.
CorrelatedNoise
correlatedNoise(const Grid& frame, int search_window, int threads)
{
  CorrelatedNoise out;
  const int lag = dilationReferenceLag(frame.width);
  const NoiseCorrelation c = estimateNoiseCorrelation(frame, tuned::kDilationCorrelationStep, threads);
  const float far = c.scale[lag - 1] * c.scale[lag - 1];
  if (!(far > 0.0f) || !(c.scale[0] * c.scale[0] < tuned::kCorrelatedVarianceRatio * far))
    return out;
  std::array<float, 2 * tuned::kDilationMaxLag + 1> rho{};
  for (int l = lag - 1; l >= 1; --l) {
    const float ratio = c.scale[l - 1] * c.scale[l - 1] / far;
    rho[l] = std::clamp((6.0f - 6.0f * ratio + 2.0f * rho[2 * l]) / 8.0f, 0.0f, 1.0f);
  }
  // Separable: the correlation area in 2D is the square of the line's.
  float line = 1.0f;
  for (int l = 1; l < lag; ++l)
    line += 2.0f * rho[l];
  out.area = line * line;
  // A plane over the search window absorbs the noise shared at about half its width.
  out.residual = std::max(1.0f - rho[std::min(search_window / 2, lag - 1)], 1.0f / out.area);
  return out;
}

} // namespace

void
propagateUncertainty(FrameContext& ctx)
{
  Workspace& workspace = ctx.workspace;
  const std::size_t n = ctx.n;
  const Grid& current = ctx.current();
  std::vector<float>& height = workspace.height_sigma;
  const bool first = ctx.iteration == 0;
  const bool prior = first && workspace.prior_sigma.size() == n;
  if (first)
    height.assign(n, 0.0f);
  const CorrelatedNoise noise =
      first && !prior ? correlatedNoise(current, ctx.parameters.search_window, ctx.threads) : CorrelatedNoise();
  const float* given = prior ? workspace.prior_sigma.data() : nullptr;
  const float* sigma = workspace.sigma.data(); // the noise profile's sigma times similarity_scale
  const float unscale = 1.0f / (ctx.parameters.similarity_scale * std::sqrt(noise.residual));
  const float* r = workspace.spread.inverse_count.data();
  float* out = height.data();
#pragma omp parallel for schedule(static) num_threads(ctx.threads)
  for (std::size_t i = 0; i < n; ++i) {
    if (!current.valid[i]) {
      out[i] = std::numeric_limits<float>::quiet_NaN();
      continue;
    }
    if (!first || (given && std::isfinite(given[i]))) {
      // A pass over filtered points: their errors are shared over the window (each is the mean
      // of a window that overlaps its neighbours' almost wholly), so the mean keeps them.
      if (first)
        out[i] = given[i];
      continue;
    }
    // The first pass over measured points: the mean of N independent candidates of the noise's
    // variance (r = 1 / N; 0 where the point has no candidate and keeps its own noise), each
    // correlated with `area` pixels around it.
    const float in = sigma[i] * unscale;
    out[i] = in * std::sqrt(r[i] > 0.0f ? std::min(1.0f, r[i] * noise.area) : 1.0f);
  }
}

void
uncertaintyAlongMoves(FrameContext& ctx, Displacement displacement)
{
  Workspace& workspace = ctx.workspace;
  const std::size_t n = ctx.n;
  const Grid& g = ctx.current();
  const NormalField& normals = workspace.normals;
  std::vector<float>& out = workspace.run.uncertainty;
  out.resize(n);
  const bool rays = displacement == Displacement::line_of_sight;
  // applyOffsets divides the height by |cos(normal, ray)|, bounded below as here.
  const float bound = std::max(ctx.parameters.line_of_sight_min_cos, tuned::kLineOfSightMinCosFloor);
  const float ox = ctx.viewpoint[0], oy = ctx.viewpoint[1], oz = ctx.viewpoint[2];
#pragma omp parallel for schedule(static) num_threads(ctx.threads)
  for (std::size_t i = 0; i < n; ++i) {
    float s = workspace.height_sigma[i];
    if (rays && g.valid[i] && std::isfinite(normals.nx[i])) {
      const float vx = g.x[i] - ox, vy = g.y[i] - oy, vz = g.z[i] - oz;
      const float len = std::sqrt(vx * vx + vy * vy + vz * vz);
      const float c = len > 0.0f ? std::fabs(vx * normals.nx[i] + vy * normals.ny[i] + vz * normals.nz[i]) / len : 1.0f;
      s /= std::max(c, bound);
    }
    out[i] = s;
  }
}

} // namespace detail
} // namespace range_nlm
