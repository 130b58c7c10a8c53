// Stage::offsets: the filtered normal offsets of the current frame's points.
#include "stages.h"

namespace range_nlm
{

void
detail::computeFrameOffsets(FrameContext& ctx)
{
  const FilterParameters& parameters = ctx.parameters;
  Workspace& workspace = ctx.workspace;
  const std::vector<float>& patch_gate = gateInto(ctx, parameters.patch_edge_gate, workspace.sigma, workspace.patch_gate);
  computeOffsets(ctx.current(), workspace.normals, ctx.terms, parameters.search_window, parameters.patch_size,
                 parameters.evaluation, ctx.threads, ctx.active, workspace.offsets, patch_gate,
                 &workspace.window_planes, parameters.uncertainty ? &workspace.spread : nullptr);
}

} // namespace range_nlm
