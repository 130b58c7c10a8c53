// Isolated points (FilterParameters::outlier_sigmas): found against the frame's noise profile and
// the point's 8-neighbours, moved along their ray onto their neighbours' surface.
#include "internal.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace range_nlm
{

namespace
{
/// Adjacent pairs (right and down neighbours) of the 5 x 5 window around a pixel.
constexpr int kSurroundReach = 2;
/// An outlier must also be farther from every neighbour than this many times the median range
/// step between adjacent pixels of its 5 x 5 surroundings.
constexpr float kSurroundSteps = 4.0f;
} // namespace

std::size_t
correctIsolatedPoints(Grid& grid, const NoiseProfile& profile, float sigmas, const Viewpoint& viewpoint)
{
  return detail::correctIsolatedPoints(grid, profile, sigmas, viewpoint, {}, 1);
}

std::size_t
detail::correctIsolatedPoints(Grid& grid, const NoiseProfile& profile, float sigmas, const Viewpoint& viewpoint,
                              const std::vector<unsigned char>& active, int threads)
{
  const int width = grid.width, height = grid.height;
  const std::size_t n = grid.size();
  if (!(sigmas > 0.0f) || profile.empty() || width <= 0 || height <= 0)
    return 0;
  threads = detail::resolveThreads(threads);
  std::vector<float> rho(n, 0.0f), tolerance(n, 0.0f);
  (void)threads;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::size_t i = 0; i < n; ++i)
    if (grid.valid[i]) {
      const float dx = grid.x[i] - viewpoint[0], dy = grid.y[i] - viewpoint[1], dz = grid.z[i] - viewpoint[2];
      rho[i] = std::sqrt(dx * dx + dy * dy + dz * dz);
    }
  {
    const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(n), block = 4096;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::ptrdiff_t lo = 0; lo < size; lo += block)
      detail::interpolateProfile(profile.range, profile.sigma, &rho[lo], &tolerance[lo],
                                 static_cast<std::size_t>(std::min(block, size - lo)));
  }
  const auto validAt = [&](int u, int v) {
    return u >= 0 && v >= 0 && u < width && v < height && grid.valid[static_cast<std::size_t>(v) * width + u];
  };
  // The new range of every outlier (0 elsewhere), from the input's ranges only: rows are
  // independent, so the result does not depend on the number of threads.
  std::vector<float> target(n, 0.0f);
#pragma omp parallel num_threads(threads)
  {
    std::vector<float> steps;
#pragma omp for schedule(dynamic, 8)
    for (int v = 0; v < height; ++v)
      for (int u = 0; u < width; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * width + u;
        if (!grid.valid[i] || (!active.empty() && !active[i]) || !(rho[i] > 0.0f))
          continue;
        const float r = rho[i], tol = sigmas * tolerance[i];
        // Close to a neighbour, or to the straight continuation of a neighbour's line through
        // the next pixel beyond it (a surface steep to the ray): not an outlier.
        float neighbours[8];
        int count = 0;
        bool agrees = false;
        for (int dv = -1; dv <= 1 && !agrees; ++dv)
          for (int du = -1; du <= 1; ++du) {
            if ((du == 0 && dv == 0) || !validAt(u + du, v + dv))
              continue;
            const float near = rho[static_cast<std::size_t>(v + dv) * width + u + du];
            neighbours[count++] = near;
            if (std::fabs(near - r) <= tol) {
              agrees = true;
              break;
            }
            if (validAt(u + 2 * du, v + 2 * dv)) {
              const float far = rho[static_cast<std::size_t>(v + 2 * dv) * width + u + 2 * du];
              if (std::fabs(2.0f * near - far - r) <= tol) {
                agrees = true;
                break;
              }
            }
          }
        if (agrees || count < 2)
          continue;
        // Surroundings whose own range steps are large (a surface at a grazing angle, where the
        // noise along the ray exceeds the profile's) keep their points.
        steps.clear();
        for (int b = v - kSurroundReach; b <= v + kSurroundReach; ++b)
          for (int a = u - kSurroundReach; a <= u + kSurroundReach; ++a) {
            if (!validAt(a, b) || (a == u && b == v))
              continue;
            const float ra = rho[static_cast<std::size_t>(b) * width + a];
            if (a < u + kSurroundReach && validAt(a + 1, b) && !(a + 1 == u && b == v))
              steps.push_back(std::fabs(rho[static_cast<std::size_t>(b) * width + a + 1] - ra));
            if (b < v + kSurroundReach && validAt(a, b + 1) && !(a == u && b + 1 == v))
              steps.push_back(std::fabs(rho[static_cast<std::size_t>(b + 1) * width + a] - ra));
          }
        if (!steps.empty()) {
          std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
          const float typical = kSurroundSteps * steps[steps.size() / 2];
          if (std::any_of(neighbours, neighbours + count, [&](float q) { return std::fabs(q - r) <= typical; }))
            continue;
        }
        // The median neighbour; of two middle ones the one nearer the point (a mean of two
        // could fall between two surfaces).
        for (int a = 1; a < count; ++a) // insertion sort of at most 8 values
          for (int b = a; b > 0 && neighbours[b] < neighbours[b - 1]; --b)
            std::swap(neighbours[b], neighbours[b - 1]);
        const float low = neighbours[(count - 1) / 2], high = neighbours[count / 2];
        target[i] = std::fabs(low - r) <= std::fabs(high - r) ? low : high;
      }
  }
  std::size_t moved = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!(target[i] > 0.0f))
      continue;
    const float f = target[i] / rho[i];
    grid.x[i] = viewpoint[0] + (grid.x[i] - viewpoint[0]) * f;
    grid.y[i] = viewpoint[1] + (grid.y[i] - viewpoint[1]) * f;
    grid.z[i] = viewpoint[2] + (grid.z[i] - viewpoint[2]) * f;
    ++moved;
  }
  return moved;
}

} // namespace range_nlm
