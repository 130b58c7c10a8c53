// Isolated points (FilterParameters::outlier_sigmas): found against the frame's noise profile and
// the point's 8-neighbours, moved along their ray onto their neighbours' surface. The step's parts
// are in outlier_surface_test.cpp, outlier_candidates.cpp and outlier_side_vote.cpp.
#include "outliers.h"

#include <cmath>
#include <limits>
#include <vector>

namespace range_nlm
{

std::size_t
correctIsolatedPoints(Grid& grid, const NoiseProfile& profile, float sigmas, const Viewpoint& viewpoint)
{
  return detail::correctIsolatedPoints(grid, profile, sigmas, viewpoint, {}, 1);
}

std::size_t
detail::correctIsolatedPoints(Grid& grid, const NoiseProfile& profile, float sigmas, const Viewpoint& viewpoint,
                              const std::vector<unsigned char>& active, int threads)
{
  const std::vector<IsolatedPoint> found = findIsolatedPoints(grid, profile, sigmas, viewpoint, active, threads);
  moveIsolatedPoints(grid, found, viewpoint);
  return found.size();
}

void
detail::moveIsolatedPoints(Grid& grid, const std::vector<IsolatedPoint>& points, const Viewpoint& viewpoint)
{
  for (const IsolatedPoint& q : points) {
    const std::size_t i = q.index;
    const float dx = grid.x[i] - viewpoint[0], dy = grid.y[i] - viewpoint[1], dz = grid.z[i] - viewpoint[2];
    const float f = q.range / std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!(f > 0.0f && f < std::numeric_limits<float>::infinity()))
      continue;
    grid.x[i] = viewpoint[0] + dx * f;
    grid.y[i] = viewpoint[1] + dy * f;
    grid.z[i] = viewpoint[2] + dz * f;
  }
}

std::vector<detail::IsolatedPoint>
detail::findIsolatedPoints(const Grid& grid, const NoiseProfile& profile, float sigmas, const Viewpoint& viewpoint,
                           const std::vector<unsigned char>& active, int threads)
{
  std::vector<float> rho;
  return findIsolatedPoints(grid, profile, sigmas, viewpoint, active, threads, rho);
}

std::vector<detail::IsolatedPoint>
detail::findIsolatedPoints(const Grid& grid, const NoiseProfile& profile, float sigmas, const Viewpoint& viewpoint,
                           const std::vector<unsigned char>& active, int threads, std::vector<float>& rho)
{
  const int width = grid.width, height = grid.height;
  if (!(sigmas > 0.0f) || profile.empty() || width <= 0 || height <= 0)
    return {};
  threads = detail::resolveThreads(threads);
  detail::rangesOf(grid, viewpoint, threads, rho);
  // A range of 0 marks a point the test leaves alone and does not compare with: invalid, at the
  // viewpoint, or so far that its range overflows.
  float* __restrict r = rho.data();
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(rho.size());
#pragma omp parallel for simd schedule(static) num_threads(threads)
  for (std::ptrdiff_t i = 0; i < size; ++i)
    r[i] = r[i] < std::numeric_limits<float>::infinity() ? r[i] : 0.0f;
  const OutlierFrame frame{rho, width, height, sigmas, profile, medianRayAngle(grid, rho, threads)};
  return voteSides(frame, findOutlierCandidates(grid, frame, active, threads));
}

} // namespace range_nlm
