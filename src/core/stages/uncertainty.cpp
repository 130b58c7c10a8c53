// The per-point uncertainty (FilterParameters::uncertainty; docs/method.md, "Per-point
// uncertainty"): each pass's weights carried into the standard deviation of every point's height.
#include "stages.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace range_nlm
{
namespace detail
{
namespace
{

/// The variance of a weighted mean of candidates whose errors share a common part: sigma_in^2 the
/// variance of a point's error before the pass, v the weighted variance of its candidates' heights
/// about their mean and r = sum w^2 / (sum w)^2 (one over their effective number N). The part of
/// the candidates' errors that varies among them is estimated without bias by v N / (N - 1) and
/// is averaged down to v / (N - 1); the rest, sigma_in^2 - v N / (N - 1), is common to them and
/// stays. Their sum is sigma_in^2 - v, never below what the varying part alone leaves.
float
passVariance(float sigma_in2, float v, float r)
{
  const float reduced = r < 1.0f ? v * r / (1.0f - r) : 0.0f; // v / (N - 1), N = 1 / r
  return std::max(sigma_in2 - v, reduced);
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
  const float* given = prior ? workspace.prior_sigma.data() : nullptr;
  const float* sigma = workspace.sigma.data(); // the noise profile's sigma times similarity_scale
  const float unscale = 1.0f / ctx.parameters.similarity_scale;
  const float* v = workspace.spread.variance.data();
  const float* r = workspace.spread.inverse_count.data();
  float* out = height.data();
#pragma omp parallel for schedule(static) num_threads(ctx.threads)
  for (std::size_t i = 0; i < n; ++i) {
    if (!current.valid[i]) {
      out[i] = std::numeric_limits<float>::quiet_NaN();
      continue;
    }
    // Before the first pass: the measurement's own noise (or the dilated passes' result).
    float in = first ? sigma[i] * unscale : out[i];
    if (given && std::isfinite(given[i]))
      in = given[i];
    // Points without candidates (no normal, inactive) keep their uncertainty: r is 0 there.
    out[i] = r[i] > 0.0f ? std::sqrt(passVariance(in * in, v[i], r[i])) : in;
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
