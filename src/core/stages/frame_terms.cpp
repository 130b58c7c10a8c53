// Stage::frame_terms: the frame weights Psi_k and, in the range-adaptive model, the per-point
// 1 / d^2 and 1 / s^2 maps of every frame and the patch guide.
#include "stages.h"

#include "../fast_math.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace range_nlm
{
namespace detail
{
namespace
{

/// Whether frame k moved against the current frame and how much larger its frame-to-frame noise
/// is than its spatial noise (at least 1).
struct NeighbourChange
{
  bool moved = false;
  float ratio = 1.0f;
};

/// The differences of frame k along the current normals (workspace.along, where compared), the
/// motion test and the frame-to-frame noise ratio against its sigma map `sig`. Guarded: whether
/// frame k moved is the run's analysis of the input frames (analyseFrameChange, before the
/// levelling) where there is one, else the motion test.
NeighbourChange
compareWithCurrent(FrameContext& ctx, int k, const std::vector<float>& sig)
{
  const CrossFrameBandwidth mode = ctx.parameters.cross_frame_bandwidth;
  const bool guarded = mode == CrossFrameBandwidth::guarded;
  const bool compared = k != ctx.center && (guarded || mode == CrossFrameBandwidth::temporal);
  Workspace& workspace = ctx.workspace;
  const Grid& current = ctx.current();
  std::vector<float>& along = workspace.along;
  if (compared)
    alongNormals(current, workspace.normals, *ctx.frames[k], ctx.threads, along);
  const std::vector<signed char>& known_moved = workspace.frames_moved;
  const int analysed =
      guarded && known_moved.size() == static_cast<std::size_t>(ctx.count) ? known_moved[k] : -1;
  NeighbourChange change;
  change.moved = analysed == 1;
  if (compared && analysed != 1) {
    const FrameComparison comparison =
        compareAlong(along, current.width, current.height, sig.data(), guarded && analysed < 0, ctx.threads);
    change.moved = comparison.moved;
    change.ratio = std::max(1.0f, comparison.ratio);
  }
  return change;
}

/// 1 / d^2 of frame k per point into workspace.inverse_d2[k]: d from its profile's extent map
/// `ext` at the centre point's range; with a frame-to-frame noise ratio above 1 it also spans the
/// distance two samples of one surface point have from frame to frame (2 s^2 more in d^2).
void
inverseDistanceMap(FrameContext& ctx, int k, const std::vector<float>& ext, const std::vector<float>& sig,
                   float ratio)
{
  const bool cross = ratio > 1.0f;
  std::vector<float>& map = ctx.workspace.inverse_d2[k];
  map.resize(ctx.n);
  float* __restrict out = map.data();
  const float* __restrict e = ext.data();
  const float* __restrict g = sig.data();
  const float* __restrict r = ctx.workspace.ranges.data();
  const float ds = ctx.parameters.distance_scale, ss = ctx.parameters.similarity_scale * ratio;
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(ctx.n);
#pragma omp parallel for simd schedule(static) num_threads(ctx.threads)
  for (std::ptrdiff_t i = 0; i < size; ++i) {
    const float d = ds * e[i] * r[i];
    const float s = ss * g[i];
    out[i] = inverseSquareInline(cross ? std::sqrt(d * d + 2.0f * s * s) : d);
  }
}

/// Guarded: no weight from frame k for a point whose surroundings changed from this frame to
/// frame k by far more than the noise (d = 0: only an exact match would keep weight); the
/// changed pixels into workspace.changed.
void
dropChangedPixels(FrameContext& ctx, int k, const std::vector<float>& sig, float ratio)
{
  Workspace& workspace = ctx.workspace;
  const Grid& current = ctx.current();
  std::vector<unsigned char>& changed = workspace.changed;
  markChangedPixels(workspace.along, current.width, current.height, workspace.profile_sigma.data(), sig.data(), ratio,
                    ctx.threads, changed);
  const float none = inverseSquareInline(0.0f);
  float* __restrict out = workspace.inverse_d2[k].data();
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(ctx.n);
#pragma omp parallel for simd schedule(static) num_threads(ctx.threads)
  for (std::ptrdiff_t i = 0; i < size; ++i)
    out[i] = changed[i] ? none : out[i];
}

/// 1 / s^2 of frame k per point into workspace.inverse_s2[k], from its sigma map `sig` raised by
/// its frame-to-frame noise ratio.
void
inverseSimilarityMap(FrameContext& ctx, int k, const std::vector<float>& sig, float ratio)
{
  std::vector<float>& map = ctx.workspace.inverse_s2[k];
  map.resize(ctx.n);
  float* __restrict out = map.data();
  const float* __restrict g = sig.data();
  const float ss = ctx.parameters.similarity_scale * ratio;
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(ctx.n);
  const std::vector<float>& factor = ctx.workspace.similarity_factor;
  if (factor.size() == ctx.n) {
    // similarity_spread: the factor from the patch spread at the point's range.
    const float* __restrict f = factor.data();
#pragma omp parallel for simd schedule(static) num_threads(ctx.threads)
    for (std::ptrdiff_t i = 0; i < size; ++i)
      out[i] = inverseSquareInline(ratio * f[i] * g[i]);
    return;
  }
#pragma omp parallel for simd schedule(static) num_threads(ctx.threads)
  for (std::ptrdiff_t i = 0; i < size; ++i)
    out[i] = inverseSquareInline(ss * g[i]);
}

/// FilterParameters::similarity_spread: per point the factor on a frame's sigma that gives s,
/// min(similarity_scale, sqrt(similarity_spread) * spread(rho_i) / sigma(rho_i)), from the current
/// frame's patch spread profile (its points and the normals of this pass) into
/// workspace.similarity_factor. Only in the first pass over the sensor's own noise, independent
/// from pixel to pixel: after a pass, and where the dilated passes or the multiscale run took
/// over (correlated or strong noise; Workspace::correlated_input), neighbouring patches share
/// their noise, and the lower quartile of Sim to the candidates understates how far apart the
/// patches of one surface are. Elsewhere empty: s = similarity_scale * sigma.
void
similarityFactorMap(FrameContext& ctx)
{
  Workspace& workspace = ctx.workspace;
  std::vector<float>& factor = workspace.similarity_factor;
  factor.clear();
  const FilterParameters& p = ctx.parameters;
  if (!(p.similarity_spread > 0.0f) || !ctx.adaptive || !ctx.own_s || ctx.iteration > 0 ||
      workspace.correlated_input)
    return;
  estimatePatchSpread(ctx.current(), workspace.normals, p.search_window, p.patch_size, p.bandwidth_samples,
                      p.seed + 104729u, ctx.viewpoint, ctx.threads, tuned::kSpreadQuantile, workspace.spread_range,
                      workspace.spread_value);
  if (workspace.spread_range.empty())
    return;
  std::vector<float>& spread = workspace.other_sigma; // scratch: the frames' terms fill it afterwards
  profileMap(ctx, workspace.spread_range, workspace.spread_value, workspace.ranges, spread);
  factor.resize(ctx.n);
  const float* __restrict e = spread.data();
  const float* __restrict g = workspace.profile_sigma.data();
  float* __restrict out = factor.data();
  const float scale = p.similarity_scale, root = std::sqrt(p.similarity_spread);
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(ctx.n);
#pragma omp parallel for simd schedule(static) num_threads(ctx.threads)
  for (std::ptrdiff_t i = 0; i < size; ++i) {
    const float wanted = root * e[i];
    out[i] = g[i] > 0.0f && wanted < scale * g[i] ? wanted / g[i] : scale;
  }
}

/// Per-point bandwidths of frame k from its profile at the centre point's range; a bandwidth
/// given by the user stays global. Another frame's noise is its spatial noise, raised to its
/// frame-to-frame noise where that is larger (spatially correlated noise): its patches then get
/// s from that noise, and its points a d that also spans the distance two samples of one surface
/// point have from frame to frame. The differences along the normals are taken once, for the
/// motion test, the ratio (against the profile's sigma at the centre points' ranges) and the
/// per-pixel test of change.
void
addBandwidthMaps(FrameContext& ctx, int k, FrameTerm& term)
{
  Workspace& workspace = ctx.workspace;
  const bool guarded = ctx.parameters.cross_frame_bandwidth == CrossFrameBandwidth::guarded;
  const bool compared =
      k != ctx.center && (guarded || ctx.parameters.cross_frame_bandwidth == CrossFrameBandwidth::temporal);
  // The current frame's sigma and extent maps are the noise maps' (workspace.profile_sigma,
  // workspace.center_extent); another frame's are taken here, in one scan.
  std::vector<float>& sig = k == ctx.center ? workspace.profile_sigma : workspace.other_sigma;
  std::vector<float>& ext = k == ctx.center ? workspace.center_extent : workspace.profile_extent;
  if (k != ctx.center && (ctx.own_d || ctx.own_s || compared))
    profileMap(ctx, ctx.profiles[k].range, ctx.profiles[k].sigma, workspace.ranges, sig,
               ctx.own_d ? &ctx.profiles[k].extent : nullptr, ctx.own_d ? &ext : nullptr);
  const NeighbourChange change = compareWithCurrent(ctx, k, sig);
  if (ctx.own_d) {
    inverseDistanceMap(ctx, k, ext, sig, change.ratio);
    if (k != ctx.center && guarded) {
      dropChangedPixels(ctx, k, sig, change.ratio);
      addToPatchGuide(ctx, k, sig, change.ratio, change.moved);
    }
    term.inverse_distance2 = &workspace.inverse_d2[k];
  }
  if (ctx.own_s) {
    inverseSimilarityMap(ctx, k, sig, change.ratio);
    term.inverse_similarity2 = &workspace.inverse_s2[k];
  }
}

} // namespace
} // namespace detail

void
detail::buildFrameTerms(FrameContext& ctx)
{
  Workspace& workspace = ctx.workspace;
  if (workspace.inverse_d2.size() < static_cast<std::size_t>(ctx.count))
    workspace.inverse_d2.resize(ctx.count), workspace.inverse_s2.resize(ctx.count);
  float s_max = 0.0f;
  for (int k = 0; k < ctx.count; ++k)
    if (ctx.usable[k])
      s_max = std::max(s_max, ctx.bandwidths[k].similarity);
  ctx.terms.clear();
  ctx.weights.assign(ctx.count, 0.0f);
  int neighbours = 0; // usable frames other than the current one
  for (int k = 0; k < ctx.count; ++k)
    neighbours += ctx.usable[k] && k != ctx.center ? 1 : 0;
  // Built only where it can be used (kGuideMinFrames): radius 1 does no work for it.
  ctx.may_guide = ctx.parameters.patch_guide && neighbours >= tuned::kGuideMinFrames;
  similarityFactorMap(ctx);
  ctx.guide_frames = 0;
  for (int k = 0; k < ctx.count; ++k) {
    if (!ctx.usable[k])
      continue;
    const Bandwidths& b = ctx.bandwidths[k];
    ctx.weights[k] = temporalDistanceWeight(k, ctx.center) * temporalNoiseWeight(b.similarity, s_max);
    FrameTerm term{k == ctx.center ? &ctx.current() : ctx.frames[k], b.distance, b.similarity, ctx.weights[k]};
    // (A temporal search window as wide as the search window or wider is the search window.)
    if (k != ctx.center && ctx.parameters.temporal_search_window < ctx.parameters.search_window)
      term.search_window = ctx.parameters.temporal_search_window;
    if (ctx.adaptive)
      addBandwidthMaps(ctx, k, term);
    ctx.terms.push_back(term);
  }
  finishPatchGuide(ctx);
  if (ctx.iteration == 0) {
    workspace.run.bandwidths = ctx.bandwidths;
    workspace.run.frame_weights = ctx.weights;
  }
}

} // namespace range_nlm
