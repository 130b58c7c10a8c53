// The patch guide of the guarded cross-frame bandwidths (docs/method.md, "The patch guide"): the
// grid the other frames' patches are compared with, the per-pixel weighted mean of the current
// frame's points and the unchanged points of the neighbours that did not move.
#include "stages.h"

#include <algorithm>
#include <cmath>

namespace range_nlm
{

void
detail::addToPatchGuide(FrameContext& ctx, int k, const std::vector<float>& sig, float ratio, bool moved)
{
  // A frame that did not move enters the guide with its points where the test found no change
  // within kGuideMargin pixels and the point's own difference is within kGuideTolerance times
  // the test's threshold (the 3 x 3 vote passes a lone pixel that changed, e.g. at the leading
  // edge of an object in a dilated pass), weighted by the inverse of its noise variance relative
  // to the current frame's, (s_c / s_k)^2, at most 1 (a smoothed neighbour does not outweigh the
  // current frame).
  const float s_k = ctx.bandwidths[k].similarity, s_c = ctx.bandwidths[ctx.center].similarity;
  if (!ctx.may_guide || moved || !(s_k > 0.0f && s_c > 0.0f && std::isfinite(s_k) && std::isfinite(s_c)))
    return;
  Workspace& workspace = ctx.workspace;
  const Grid& current = ctx.current();
  const int threads = ctx.threads;
  Grid& guide = workspace.guide;
  std::vector<float>& guide_weight = workspace.guide_weight;
  // The sums start with the current frame (weight 1).
  if (ctx.guide_frames++ == 0) {
    copyGrid(current, guide, threads);
    guide_weight.assign(ctx.n, 1.0f);
  }
  std::vector<unsigned char>& widened = workspace.widened;
  widenMask(workspace.changed, current.width, current.height, tuned::kGuideMargin, threads, widened);
  const float w = std::min(1.0f, (s_c / s_k) * (s_c / s_k));
  const Grid& other = *ctx.frames[k];
  const float limit = tuned::kGuideTolerance * tuned::kChangeSigmas * 1.41421356f * ratio;
  const float* __restrict sigma_c = workspace.profile_sigma.data();
  const float* __restrict g = sig.data();
  const float* __restrict difference = workspace.along.data();
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(ctx.n);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::ptrdiff_t i = 0; i < size; ++i)
    if (guide.valid[i] && other.valid[i] && !widened[i] &&
        std::fabs(difference[i]) <= limit * std::max(sigma_c[i], g[i])) {
      guide.x[i] += w * other.x[i];
      guide.y[i] += w * other.y[i];
      guide.z[i] += w * other.z[i];
      guide_weight[i] += w;
    }
}

void
detail::finishPatchGuide(FrameContext& ctx)
{
  // With fewer neighbours in it, each would find a large share of its own noise in the guide and
  // its candidates would lean towards that instead (kGuideMinFrames).
  if (ctx.guide_frames < tuned::kGuideMinFrames)
    return;
  Grid& guide = ctx.workspace.guide;
  const std::vector<float>& guide_weight = ctx.workspace.guide_weight;
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(ctx.n);
#pragma omp parallel for schedule(static) num_threads(ctx.threads)
  for (std::ptrdiff_t i = 0; i < size; ++i) {
    const float inverse = 1.0f / guide_weight[i];
    guide.x[i] *= inverse;
    guide.y[i] *= inverse;
    guide.z[i] *= inverse;
  }
  for (FrameTerm& term : ctx.terms)
    if (term.grid != &ctx.current())
      term.patches = &guide;
}

} // namespace range_nlm
