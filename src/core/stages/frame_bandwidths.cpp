// Stage::neighbour_frames and Stage::bandwidths: each frame's scalar bandwidths (global model)
// or noise profile (range-adaptive model).
#include "stages.h"

#include <cmath>
#include <cstdint>
#include <sstream>

namespace range_nlm
{
namespace detail
{
namespace
{

Bandwidths
finishBandwidths(Bandwidths b, const FilterParameters& p)
{
  b.distance = p.distance_bandwidth > 0.0f ? p.distance_bandwidth : p.distance_scale * b.mu_d;
  b.similarity = p.similarity_bandwidth > 0.0f ? p.similarity_bandwidth : p.similarity_scale * b.sigma_s;
  // An infinite or NaN bandwidth weighs every candidate alike or none: the frame would come out
  // unchanged, or as garbage, while counted as filtered.
  if (!std::isfinite(b.distance) || !std::isfinite(b.similarity)) {
    std::ostringstream msg;
    msg << "range_nlm: the bandwidths of the frame are not finite (d = " << b.distance << ", s = " << b.similarity
        << "); its coordinates are out of the range the float arithmetic handles";
    throw UnfilterableFrame(msg.str());
  }
  return b;
}

/// The median range of the valid points of `g` (ranges `rho`).
float
medianRange(const FrameContext& ctx, const Grid& g, const std::vector<float>& rho)
{
  return medianOfNonNegative(rho.data(), g.valid.data(), g.size(), ctx.threads);
}

/// Frame k's (points `g`) noise profile: the one carried for its place in the window and this pass
/// (FilterParameters::reuse_estimates, workspace.profiles), else estimated with `seed` and kept
/// there for the stream's next frames.
NoiseProfile
frameProfile(FrameContext& ctx, int k, const Grid& g, std::uint64_t seed)
{
  Workspace& workspace = ctx.workspace;
  const int offset = k - ctx.center;
  if (const NoiseProfile* carried = carriedProfile(workspace, offset, ctx.iteration))
    return *carried;
  NoiseProfile profile = estimateNoiseProfile(g, ctx.parameters.search_window, ctx.parameters.bandwidth_samples,
                                              seed, ctx.viewpoint, ctx.threads);
  ++workspace.run.profiles_estimated;
  keepProfile(workspace, offset, ctx.iteration, profile);
  return profile;
}

/// Frame k's (points `g`) bandwidths into ctx.bandwidths[k]: from its noise profile at range
/// `rho_median` (range-adaptive model; the profile into ctx.profiles[k]), else from `normals`
/// (global model; null: g's raw normals, fitted into the current frame's buffer, which is
/// filled afterwards).
void
estimateFrame(FrameContext& ctx, int k, const Grid& g, const NormalField* normals, float rho_median)
{
  const FilterParameters& parameters = ctx.parameters;
  if (k != ctx.center)
    checkCoordinateScale(g); // the current frame's was checked first
  const std::uint64_t seed = parameters.seed + static_cast<std::uint64_t>(k - ctx.center) * 7919u;
  if (ctx.adaptive) {
    // The current frame's first pass uses the profile the outlier stage estimated on it (the same
    // sample), so that a frame's noise is estimated once per call.
    const bool as_given = k == ctx.center && ctx.iteration == 0 && ctx.frames[k] == ctx.workspace.profiled;
    ctx.profiles[k] = as_given ? currentFrameProfile(g, parameters, ctx.viewpoint, ctx.workspace)
                               : frameProfile(ctx, k, g, seed);
    Bandwidths b;
    b.sigma_s = ctx.profiles[k].sigmaAt(rho_median);
    b.mu_d = ctx.profiles[k].extentAt(rho_median) * rho_median;
    ctx.bandwidths[k] = finishBandwidths(b, parameters);
    return;
  }
  Workspace& workspace = ctx.workspace;
  if (!normals)
    estimateNormalsGated(g, parameters.normal_window, ctx.viewpoint, ctx.threads, {}, 0, workspace.normals,
                         &workspace.normal_planes);
  ctx.bandwidths[k] =
      finishBandwidths(estimateBandwidths(g, normals ? *normals : workspace.normals, parameters.search_window,
                                          parameters.bandwidth_samples, seed),
                       parameters);
}

} // namespace
} // namespace detail

const NoiseProfile&
detail::currentFrameProfile(const Grid& frame, const FilterParameters& parameters, const Viewpoint& viewpoint,
                            Workspace& workspace)
{
  NoiseProfile& profile = workspace.current_profile;
  if (profile.empty()) {
    profile = estimateNoiseProfile(frame, parameters.search_window, parameters.bandwidth_samples, parameters.seed,
                                   viewpoint, resolveThreads(parameters.threads));
    ++workspace.run.profiles_estimated;
  }
  return profile;
}

void
detail::estimateNeighbourFrames(FrameContext& ctx)
{
  Workspace& workspace = ctx.workspace;
  if (ctx.adaptive) {
    rangesOf(ctx.current(), ctx.viewpoint, ctx.threads, workspace.ranges);
    ctx.input_rho_median = medianRange(ctx, ctx.current(), workspace.ranges);
  }
  for (int k = 0; k < ctx.count; ++k) {
    if (k == ctx.center)
      continue;
    try {
      estimateFrame(ctx, k, *ctx.frames[k], nullptr, ctx.input_rho_median);
    } catch (const UnfilterableFrame&) {
      ctx.usable[k] = false; // an all-NaN neighbour contributes nothing
    }
  }
}

void
detail::estimateCurrentFrame(FrameContext& ctx)
{
  const Grid& current = ctx.current();
  if (!ctx.adaptive) {
    estimateFrame(ctx, ctx.center, current, &ctx.workspace.normals, 0.0f);
    return;
  }
  // The neighbours' stage took the first iteration's ranges.
  std::vector<float>& rho = ctx.workspace.ranges;
  const bool known = ctx.iteration == 0 && ctx.count > 1;
  if (!known)
    rangesOf(current, ctx.viewpoint, ctx.threads, rho);
  estimateFrame(ctx, ctx.center, current, nullptr, known ? ctx.input_rho_median : medianRange(ctx, current, rho));
}

} // namespace range_nlm
