// Stage::displacement: the current frame's points moved by their offsets (applyOffsets).
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
/// applyOffsets along the normals for points [0, n), branch-free so that it vectorizes (every
/// load is unconditional): points that do not move keep their coordinates. With Clamped, h is
/// clamped to +/- bound[i] first.
template <bool Clamped>
void
moveAlongNormals(float* __restrict x, float* __restrict y, float* __restrict z, const unsigned char* __restrict valid,
                 const float* __restrict nx, const float* __restrict ny, const float* __restrict nz,
                 const float* __restrict hs, const float* __restrict bound, std::ptrdiff_t n)
{
  const float largest = std::numeric_limits<float>::max();
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const float raw = hs[i];
    float h = raw;
    if constexpr (Clamped) {
      const float b = bound[i];
      h = h < -b ? -b : h;
      h = h > b ? b : h; // NaN stays NaN
    }
    const float v = valid[i];
    const bool moves = (v > 0.0f) & (h != 0.0f) & (std::fabs(h) <= largest);
    const float px = x[i], py = y[i], pz = z[i];
    const float qx = px - h * nx[i], qy = py - h * ny[i], qz = pz - h * nz[i];
    x[i] = moves ? qx : px;
    y[i] = moves ? qy : py;
    z[i] = moves ? qz : pz;
  }
}

/// applyOffsets along the line of sight for points [0, n), branch-free as moveAlongNormals: each
/// point moves along its ray from the viewpoint onto the plane (q - p) . n = -h, by t = -h / cos
/// with |cos| at least min_cos (at grazing angles h / cos would amplify any normal error); with
/// Clamped, h and t are clamped to +/- limit[i].
template <bool Clamped>
void
moveAlongRays(float* __restrict x, float* __restrict y, float* __restrict z, const unsigned char* __restrict valid,
              const float* __restrict nx, const float* __restrict ny, const float* __restrict nz,
              const float* __restrict hs, const float* __restrict limit, const Viewpoint& viewpoint, float min_cos,
              std::ptrdiff_t n)
{
  const float largest = std::numeric_limits<float>::max();
  const float ox = viewpoint[0], oy = viewpoint[1], oz = viewpoint[2];
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    float h = hs[i];
    if constexpr (Clamped) {
      const float b = limit[i];
      h = h < -b ? -b : h;
      h = h > b ? b : h; // NaN stays NaN
    }
    const float px = x[i], py = y[i], pz = z[i];
    float vx = px - ox, vy = py - oy, vz = pz - oz;
    const float len = std::sqrt(vx * vx + vy * vy + vz * vz);
    const float v = valid[i];
    const bool moves = (v > 0.0f) & (h != 0.0f) & (std::fabs(h) <= largest) & (len > 0.0f);
    vx /= len, vy /= len, vz /= len;
    float c = vx * nx[i] + vy * ny[i] + vz * nz[i];
    const float signed_bound = c < 0.0f ? -min_cos : min_cos;
    c = std::fabs(c) < min_cos ? signed_bound : c;
    float t = -h / c;
    if constexpr (Clamped) {
      const float b = limit[i];
      t = t < -b ? -b : t;
      t = t > b ? b : t;
    }
    x[i] = moves ? px + t * vx : px;
    y[i] = moves ? py + t * vy : py;
    z[i] = moves ? pz + t * vz : pz;
  }
}
} // namespace
} // namespace detail

void
applyOffsets(Grid& grid, const NormalField& normals, const std::vector<float>& offsets,
             Displacement displacement, const Viewpoint& viewpoint, const std::vector<float>& limit,
             float min_cos)
{
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(grid.size());
  if (displacement != Displacement::line_of_sight) { // automatic: one frame here
    const auto move = limit.empty() ? detail::moveAlongNormals<false> : detail::moveAlongNormals<true>;
    const std::ptrdiff_t block = 4096;
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t lo = 0; lo < n; lo += block)
      move(&grid.x[lo], &grid.y[lo], &grid.z[lo], &grid.valid[lo], &normals.nx[lo], &normals.ny[lo],
           &normals.nz[lo], &offsets[lo], limit.empty() ? nullptr : &limit[lo], std::min(block, n - lo));
    return;
  }
  const auto move = limit.empty() ? detail::moveAlongRays<false> : detail::moveAlongRays<true>;
  const float bound = std::max(min_cos, tuned::kLineOfSightMinCosFloor);
  const std::ptrdiff_t block = 4096;
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t lo = 0; lo < n; lo += block)
    move(&grid.x[lo], &grid.y[lo], &grid.z[lo], &grid.valid[lo], &normals.nx[lo], &normals.ny[lo], &normals.nz[lo],
         &offsets[lo], limit.empty() ? nullptr : &limit[lo], viewpoint, bound, std::min(block, n - lo));
}

void
detail::displaceCurrentFrame(FrameContext& ctx)
{
  const FilterParameters& parameters = ctx.parameters;
  Workspace& workspace = ctx.workspace;
  std::vector<float>& limit = workspace.limit;
  if (parameters.max_displacement > 0.0f) {
    const std::vector<float>& sigma = workspace.sigma;
    const float bound = parameters.max_displacement;
    const std::size_t n = ctx.n;
    limit.resize(n);
#pragma omp parallel for schedule(static) num_threads(ctx.threads)
    for (std::size_t i = 0; i < n; ++i)
      limit[i] = bound * sigma[i];
  } else {
    limit.clear();
  }
  applyOffsets(workspace.run.output, workspace.normals, workspace.offsets, resolvedDisplacement(ctx), ctx.viewpoint,
               limit, parameters.line_of_sight_min_cos);
}

Displacement
detail::resolvedDisplacement(const FrameContext& ctx)
{
  // Automatic: along the line of sight with neighbours, along the normal for one frame.
  const bool neighbours = std::count(ctx.usable.begin(), ctx.usable.end(), true) > 1;
  return ctx.parameters.displacement != Displacement::automatic ? ctx.parameters.displacement
         : neighbours                                           ? Displacement::line_of_sight
                                                                : Displacement::normal;
}

} // namespace range_nlm
