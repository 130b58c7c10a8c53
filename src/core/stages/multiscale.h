// The building blocks of the multiscale run (multiscale.cpp), shared with its tests: the
// reduction of a frame to the next coarser scale and the carry of that scale's range corrections
// to the finer one.
#pragma once

#include "../internal.h"
#include "../tuned.h"

#include <algorithm>
#include <vector>

namespace range_nlm
{
namespace detail
{

/// What the reduction and the carry agree on: the viewpoint and the tolerance of "one surface"
/// at a range (noise sigmas of the scale's profile, at least some pixel footprints).
struct SurfaceTolerance
{
  const NoiseProfile& profile;
  float ray_angle;

  float at(float rho) const
  {
    return std::max(tuned::kScaleSurfaceSigmas * profile.sigmaAt(rho),
                    tuned::kScaleSurfaceFootprints * ray_angle * rho);
  }
};

/// What the carry of one scale's corrections reads.
struct CarrySource
{
  int width, height; // of the coarse scale
  const std::vector<float>& rho;        // reduced ranges
  const std::vector<float>& correction; // per coarse pixel, NaN = none
  const std::vector<unsigned char>& member;
  const SurfaceTolerance& tolerance;
};

/// `fine` reduced to half its width and height (rounded up): each 2 x 2 block the mean of its
/// valid points within the tolerance of the block's lower-median range (a block across a depth
/// edge takes one side); a block without a valid point is invalid. `rho` receives the fine
/// ranges; `member` (if given) marks the fine pixels that entered their block's mean.
void
reduceFrame(const Grid& fine, const Viewpoint& viewpoint, const SurfaceTolerance& tolerance, int threads,
            std::vector<float>& rho, Grid& coarse, std::vector<unsigned char>* member);

/// `fine` (ranges `fine_rho`) with every active valid point moved along its ray by the bilinear
/// mean of the corrections of the four nearest coarse points on one surface with it (or of its own
/// block, if none is and it entered the block's mean); a point with none keeps its place.
void
carryCorrections(const Grid& fine, const std::vector<float>& fine_rho, const CarrySource& source,
                 const Viewpoint& viewpoint, const std::vector<unsigned char>& active, int threads, Grid& out);

} // namespace detail
} // namespace range_nlm
