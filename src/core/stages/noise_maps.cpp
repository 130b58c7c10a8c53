// Stage::noise_maps: the current frame's per-point noise sigma, the pre-smoothing bandwidths and
// the normal gate.
#include "stages.h"

#include <algorithm>

namespace range_nlm
{

void
detail::profileMap(const FrameContext& ctx, const std::vector<float>& xs, const std::vector<float>& ys,
                   const std::vector<float>& rho, std::vector<float>& out, const std::vector<float>* ys2,
                   std::vector<float>* out2)
{
  const std::size_t n = ctx.n;
  out.resize(n);
  if (out2)
    out2->resize(n);
  interpolateProfile(xs, ys, rho.data(), out.data(), n, ctx.threads, ys2, out2 ? out2->data() : nullptr);
}

const std::vector<float>&
detail::gateInto(const FrameContext& ctx, float sigmas, const std::vector<float>& sig, std::vector<float>& gate)
{
  if (!(sigmas > 0.0f)) {
    gate.clear();
    return gate;
  }
  // (Every element is written below: resized, not cleared.)
  const std::size_t n = ctx.n;
  const float scale = ctx.parameters.similarity_scale;
  gate.resize(n);
#pragma omp parallel for schedule(static) num_threads(ctx.threads)
  for (std::size_t i = 0; i < n; ++i)
    gate[i] = sigmas * sig[i] / scale;
  return gate;
}

void
detail::computeNoiseMaps(FrameContext& ctx)
{
  const FilterParameters& parameters = ctx.parameters;
  Workspace& workspace = ctx.workspace;
  const Grid& current = ctx.current();
  const std::size_t n = ctx.n;
  const int threads = ctx.threads;
  // Local noise sigma of every centre point: for the pre-smoothing and the displacement limit.
  std::vector<float>& sigma = workspace.sigma;
  sigma.resize(n);
  if (!ctx.adaptive) {
    const float similarity = ctx.bandwidths[ctx.center].similarity;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::size_t i = 0; i < n; ++i)
      sigma[i] = similarity;
  } else {
    std::vector<float>& at = workspace.profile_sigma;
    const NoiseProfile& profile = ctx.profiles[ctx.center];
    // The current frame's extent map for its frame term too, in the same scan.
    profileMap(ctx, profile.range, profile.sigma, workspace.ranges, at, ctx.own_d ? &profile.extent : nullptr,
               ctx.own_d ? &workspace.center_extent : nullptr);
    const float scale = parameters.similarity_scale;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::size_t i = 0; i < n; ++i)
      sigma[i] = current.valid[i] ? scale * at[i] : 0.0f;
  }
  if (parameters.normal_presmooth_window > 1) {
    std::vector<float>& range_sigma = workspace.range_sigma;
    range_sigma.resize(n);
    const float range = parameters.normal_presmooth_range, scale = parameters.similarity_scale;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::size_t i = 0; i < n; ++i)
      range_sigma[i] = range * sigma[i] / scale;
  }
  if (parameters.normal_presmooth_window > 1 || ctx.adaptive)
    gateInto(ctx, parameters.normal_edge_gate, sigma, workspace.gate);
}

} // namespace range_nlm
