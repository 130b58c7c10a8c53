// Stage::presmoothing and Stage::normals: the normal fits of the current frame.
#include "stages.h"

namespace range_nlm
{

void
detail::fitRawNormals(FrameContext& ctx)
{
  Workspace& workspace = ctx.workspace;
  estimateNormalsGated(ctx.current(), ctx.parameters.normal_window, ctx.viewpoint, ctx.threads, {}, 0,
                       workspace.normals, &workspace.normal_planes);
}

void
detail::presmoothCurrentFrame(FrameContext& ctx)
{
  Workspace& workspace = ctx.workspace;
  // The padded planes of the pre-smoothing are those of the normal fits that follow (not needed
  // by then).
  presmoothAlongRays(ctx.current(), ctx.parameters.normal_presmooth_window, workspace.range_sigma, ctx.viewpoint,
                     ctx.threads, workspace.smooth, &workspace.normal_planes);
}

void
detail::fitGatedNormals(FrameContext& ctx, const Grid& points)
{
  Workspace& workspace = ctx.workspace;
  const std::vector<float>& gate = workspace.gate;
  estimateNormalsGated(points, ctx.parameters.normal_window, ctx.viewpoint, ctx.threads, gate, gate.empty() ? 0 : 2,
                       workspace.normals, &workspace.normal_planes, &workspace.first_normals);
}

} // namespace range_nlm
