// The candidates of the isolated-outlier step: the points that lie on no surface, are far from
// the surface points around them (beyond the range steps of their surroundings), and the ranges of
// their surface neighbours they may move to.
#include "outliers.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace range_nlm
{
namespace
{
/// Side of the square of the surroundings.
constexpr int kSide = 2 * tuned::kSurroundReach + 1;

/// candidate[u] = 0 for the points of row v (inside the frame) within `smallest` (the smallest
/// tolerance, that of the profile's smallest sigma) of two of their 8 neighbours: no outliers;
/// 1 for the others and the frame's border, which take the whole test.
void
markRowCandidates(const detail::OutlierFrame& frame, int v, float smallest, std::vector<unsigned char>& candidate)
{
  // One branch-free pass over the row (an invalid neighbour has range 0 and a valid point a
  // positive one).
  const int width = frame.width, height = frame.height;
  const std::vector<float>& rho = frame.rho;
  std::fill(candidate.begin(), candidate.end(), 1);
  if (v > 0 && v + 1 < height) {
    const float* __restrict above = &rho[static_cast<std::size_t>(v - 1) * width];
    const float* __restrict row = &rho[static_cast<std::size_t>(v) * width];
    const float* __restrict below = &rho[static_cast<std::size_t>(v + 1) * width];
    unsigned char* __restrict flag = candidate.data();
    for (int u = 1; u + 1 < width; ++u) {
      const float r = row[u];
      const auto close = [&](float q) { return (q > 0.0f) & (std::fabs(q - r) <= smallest); };
      const int close_ones = close(above[u - 1]) + close(above[u]) + close(above[u + 1]) + close(row[u - 1]) +
                             close(row[u + 1]) + close(below[u - 1]) + close(below[u]) + close(below[u + 1]);
      flag[u] = close_ones < 2;
    }
  }
}

/// Which pixels of the 5 x 5 surroundings of a point lie on a surface (without the point).
struct Surroundings
{
  bool on[kSide * kSide];
  bool usable(int a, int b) const { return on[(b + tuned::kSurroundReach) * kSide + a + tuned::kSurroundReach]; }
};

/// The Surroundings of point (u, v), and the range steps between their adjacent pixels on a
/// surface into `steps`. The steps are taken between points that lie on a surface: next to a
/// time-of-flight edge half the pixels may be mixed, and their steps would make every step look
/// ordinary.
void
surroundingSteps(const detail::OutlierFrame& frame, int u, int v, Surroundings& around, std::vector<float>& steps)
{
  const int width = frame.width;
  const std::vector<float>& rho = frame.rho;
  steps.clear();
  for (int b = -tuned::kSurroundReach; b <= tuned::kSurroundReach; ++b)
    for (int a = -tuned::kSurroundReach; a <= tuned::kSurroundReach; ++a)
      around.on[(b + tuned::kSurroundReach) * kSide + a + tuned::kSurroundReach] =
          (a != 0 || b != 0) && frame.validAt(u + a, v + b) && detail::onSurface(frame, u + a, v + b, u, v);
  for (int b = -tuned::kSurroundReach; b <= tuned::kSurroundReach; ++b)
    for (int a = -tuned::kSurroundReach; a <= tuned::kSurroundReach; ++a) {
      if (!around.usable(a, b))
        continue;
      const float ra = rho[static_cast<std::size_t>(v + b) * width + u + a];
      if (a < tuned::kSurroundReach && around.usable(a + 1, b))
        steps.push_back(std::fabs(rho[static_cast<std::size_t>(v + b) * width + u + a + 1] - ra));
      if (b < tuned::kSurroundReach && around.usable(a, b + 1))
        steps.push_back(std::fabs(rho[static_cast<std::size_t>(v + b + 1) * width + u + a] - ra));
    }
}

/// Whether the valid point (u, v), index i, is a candidate: on no surface, with two valid
/// neighbours, at least one neighbour on a surface, and farther from each of those than
/// tuned::kSurroundSteps times the median step of its surroundings. If so, its fields into `c`.
bool
isCandidate(const detail::OutlierFrame& frame, std::size_t i, int u, int v, std::vector<float>& steps,
            detail::OutlierCandidate& c)
{
  const int width = frame.width;
  const std::vector<float>& rho = frame.rho;
  if (detail::onSurface(frame, u, v, -1, -1))
    return false;
  const float r = rho[i];
  float neighbours[8];
  int count = 0;
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du)
      if ((du != 0 || dv != 0) && frame.validAt(u + du, v + dv))
        neighbours[count++] = rho[static_cast<std::size_t>(v + dv) * width + u + du];
  if (count < 2)
    return false;
  // Surroundings whose own range steps are large (a surface at a grazing angle, where the noise
  // along the ray exceeds the profile's) keep their points.
  Surroundings around;
  surroundingSteps(frame, u, v, around, steps);
  // The neighbours that lie on a surface themselves (next to a time-of-flight edge, half of them
  // may be mixed pixels too); none: the point stays, nothing tells where it belongs.
  int kept = 0;
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du)
      if (around.usable(du, dv)) // the ring of the 5 x 5 test: valid and on a surface
        neighbours[kept++] = rho[static_cast<std::size_t>(v + dv) * width + u + du];
  if (kept == 0)
    return false;
  // A point within those steps of one of them is on their surface.
  if (!steps.empty()) {
    std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
    const float typical = tuned::kSurroundSteps * steps[steps.size() / 2];
    if (std::any_of(neighbours, neighbours + kept, [&](float q) { return std::fabs(q - r) <= typical; }))
      return false;
  }
  for (int a = 1; a < kept; ++a) // insertion sort of at most 8 values
    for (int b = a; b > 0 && neighbours[b] < neighbours[b - 1]; --b)
      std::swap(neighbours[b], neighbours[b - 1]);
  c = detail::OutlierCandidate{i, u, v, r, kept, {}};
  std::copy(neighbours, neighbours + kept, c.ring);
  return true;
}
} // namespace

std::vector<std::vector<detail::OutlierCandidate>>
detail::findOutlierCandidates(const Grid& grid, const OutlierFrame& frame, const std::vector<unsigned char>& active,
                              int threads)
{
  const int width = frame.width, height = frame.height;
  // Most points are within the smallest tolerance (that of the profile's smallest sigma) of a
  // neighbour; the tolerance at their own range is looked up only for the others.
  const float smallest = frame.sigmas * *std::min_element(frame.profile.sigma.begin(), frame.profile.sigma.end());
  // Rows are independent and each thread's finds are merged in row order: the result does not
  // depend on the number of threads.
  std::vector<std::vector<OutlierCandidate>> rows(height);
  (void)threads;
#pragma omp parallel num_threads(detail::resolveThreads(threads))
  {
    std::vector<float> steps;
    std::vector<unsigned char> candidate(width);
#pragma omp for schedule(dynamic, 8)
    for (int v = 0; v < height; ++v) {
      markRowCandidates(frame, v, smallest, candidate);
      for (int u = 0; u < width; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * width + u;
        if (!candidate[u] || !grid.valid[i] || (!active.empty() && !active[i]) || !(frame.rho[i] > 0.0f))
          continue;
        OutlierCandidate c{};
        if (isCandidate(frame, i, u, v, steps, c))
          rows[v].push_back(c);
      }
    }
  }
  return rows;
}

} // namespace range_nlm
