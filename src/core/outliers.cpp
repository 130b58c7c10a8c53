// Isolated points (FilterParameters::outlier_sigmas): found against the frame's noise profile and
// the point's 8-neighbours, moved along their ray onto their neighbours' surface.
#include "internal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace range_nlm
{

namespace
{
/// Adjacent pairs (right and down neighbours) of the 5 x 5 window around a pixel.
constexpr int kSurroundReach = 2;
constexpr int kSide = 2 * kSurroundReach + 1;
/// An outlier must also be farther from every neighbour on a surface than this many times the
/// median range step between adjacent pixels of its 5 x 5 surroundings that lie on a surface.
constexpr float kSurroundSteps = 4.0f;
/// Reach of the surroundings that choose an outlier's side of a depth edge: 11 x 11 pixels.
constexpr int kSideReach = 5;
/// Smallest tolerance of "on a surface", in pixel footprints (range x the angle between adjacent
/// rays).
constexpr float kFootprints = 3.0f;
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
  const int width = grid.width, height = grid.height;
  std::vector<IsolatedPoint> found;
  if (!(sigmas > 0.0f) || profile.empty() || width <= 0 || height <= 0)
    return found;
  threads = detail::resolveThreads(threads);
  std::vector<float> rho;
  detail::rangesOf(grid, viewpoint, threads, rho);
  // A range of 0 marks a point the test leaves alone and does not compare with: invalid, at the
  // viewpoint, or so far that its range overflows.
  for (float& r : rho)
    r = r < std::numeric_limits<float>::infinity() ? r : 0.0f;
  // The angle between adjacent rays: the median of |p_i - p_j| / rho_i over adjacent valid pixels
  // at every 4th column of every 8th row (on a surface facing the sensor, the pixel's angular
  // size). A step along the
  // ray of a few pixel footprints is geometry (an edge of a face seen at a grazing angle, a
  // curved silhouette), not an outlier, however small the noise: without this floor a noise-free
  // frame would have its silhouettes taken for outliers.
  float ray_angle = 0.0f;
  {
    std::vector<float> angles;
    for (int v = 0; v + 1 < height; v += 8)
      for (int u = 0; u + 1 < width; u += 4) {
        const std::size_t i = static_cast<std::size_t>(v) * width + u;
        if (!(rho[i] > 0.0f))
          continue;
        for (const std::size_t j : {i + 1, i + static_cast<std::size_t>(width)})
          if (rho[j] > 0.0f) {
            const float dx = grid.x[j] - grid.x[i], dy = grid.y[j] - grid.y[i], dz = grid.z[j] - grid.z[i];
            const float angle = std::sqrt(dx * dx + dy * dy + dz * dz) / rho[i];
            if (angle < std::numeric_limits<float>::infinity())
              angles.push_back(angle);
          }
      }
    if (!angles.empty()) {
      std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
      ray_angle = angles[angles.size() / 2];
    }
  }
  const auto toleranceAt = [&](float r) { return std::max(sigmas * profile.sigmaAt(r), kFootprints * ray_angle * r); };
  // Most points are within the smallest tolerance (that of the profile's smallest sigma) of a
  // neighbour; the tolerance at their own range is looked up only for the others.
  const float smallest = sigmas * *std::min_element(profile.sigma.begin(), profile.sigma.end());
  const auto validAt = [&](int u, int v) {
    return u >= 0 && v >= 0 && u < width && v < height && rho[static_cast<std::size_t>(v) * width + u] > 0.0f;
  };
  // Whether point (a, b) agrees with its valid 8-neighbour (c, d): within `sigmas` noise sigmas at
  // its range of the neighbour's range, or of the straight continuation 2 rho_j - rho_j' of the
  // line from the pixel j' beyond the neighbour (a surface steep to the rays), j' other than pixel
  // (skip_a, skip_b).
  const auto agrees = [&](int a, int b, int c, int d, float r, float tol, int skip_a, int skip_b) {
    const float near = rho[static_cast<std::size_t>(d) * width + c];
    if (std::fabs(near - r) <= tol)
      return true;
    const int e = 2 * c - a, f = 2 * d - b;
    if (!validAt(e, f) || (e == skip_a && f == skip_b))
      return false;
    const float beyond = rho[static_cast<std::size_t>(f) * width + e];
    return std::fabs(2.0f * near - beyond - r) <= tol;
  };
  // Whether point (a, b) agrees with one of its valid 8-neighbours other than pixel (skip_a, skip_b).
  const auto agreesWithANeighbour = [&](int a, int b, int skip_a, int skip_b) {
    const float r = rho[static_cast<std::size_t>(b) * width + a];
    const float tol = toleranceAt(r);
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du) {
        const int c = a + du, d = b + dv;
        if ((du == 0 && dv == 0) || (c == skip_a && d == skip_b) || !validAt(c, d))
          continue;
        if (agrees(a, b, c, d, r, tol, skip_a, skip_b))
          return true;
      }
    return false;
  };
  // Whether point (a, b) lies on a surface: it agrees with two valid 8-neighbours other than pixel
  // (skip_a, skip_b), or with one that agrees in turn with one of its own neighbours other than
  // (a, b). Two points that agree only with each other (two mixed pixels of a time-of-flight edge
  // at similar ranges, or one in line with a mixed and a surface point by chance) are no surface.
  const auto onSurface = [&](int a, int b, int skip_a, int skip_b) {
    const float r = rho[static_cast<std::size_t>(b) * width + a];
    const float tol = toleranceAt(r);
    int lone_c = -1, lone_d = -1; // the one neighbour agreed with so far; -1: none
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du) {
        const int c = a + du, d = b + dv;
        if ((du == 0 && dv == 0) || (c == skip_a && d == skip_b) || !validAt(c, d) ||
            !agrees(a, b, c, d, r, tol, skip_a, skip_b))
          continue;
        if (lone_c >= 0)
          return true;
        lone_c = c;
        lone_d = d;
      }
    return lone_c >= 0 && agreesWithANeighbour(lone_c, lone_d, a, b);
  };
  // Rows are independent and each thread's finds are merged in row order: the result does not
  // depend on the number of threads.
  struct Candidate
  {
    std::size_t index;
    int u, v;
    float range;
    int kept;      // how many of ring[] are set
    float ring[8]; // the ranges of its 8-neighbours on a surface, ascending
  };
  std::vector<std::vector<Candidate>> rows(height);
#pragma omp parallel num_threads(threads)
  {
    std::vector<float> steps;
    std::vector<unsigned char> candidate(width);
#pragma omp for schedule(dynamic, 8)
    for (int v = 0; v < height; ++v) {
      // Inside the frame, a point within the smallest tolerance of two of its 8 neighbours is no
      // outlier: one branch-free pass over the row (an invalid neighbour has range 0 and a valid
      // point a positive one). The others, and the frame's border, take the whole test.
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
      for (int u = 0; u < width; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * width + u;
        if (!candidate[u] || !grid.valid[i] || (!active.empty() && !active[i]) || !(rho[i] > 0.0f))
          continue;
        if (onSurface(u, v, -1, -1))
          continue;
        const float r = rho[i];
        float neighbours[8];
        int count = 0;
        for (int dv = -1; dv <= 1; ++dv)
          for (int du = -1; du <= 1; ++du)
            if ((du != 0 || dv != 0) && validAt(u + du, v + dv))
              neighbours[count++] = rho[static_cast<std::size_t>(v + dv) * width + u + du];
        if (count < 2)
          continue;
        // Surroundings whose own range steps are large (a surface at a grazing angle, where the
        // noise along the ray exceeds the profile's) keep their points. The steps are taken
        // between points that lie on a surface: next to a time-of-flight edge half the pixels
        // may be mixed, and their steps would make every step look ordinary.
        steps.clear();
        bool on[kSide * kSide];
        for (int b = -kSurroundReach; b <= kSurroundReach; ++b)
          for (int a = -kSurroundReach; a <= kSurroundReach; ++a)
            on[(b + kSurroundReach) * kSide + a + kSurroundReach] =
                (a != 0 || b != 0) && validAt(u + a, v + b) && onSurface(u + a, v + b, u, v);
        const auto usable = [&](int a, int b) { return on[(b + kSurroundReach) * kSide + a + kSurroundReach]; };
        for (int b = -kSurroundReach; b <= kSurroundReach; ++b)
          for (int a = -kSurroundReach; a <= kSurroundReach; ++a) {
            if (!usable(a, b))
              continue;
            const float ra = rho[static_cast<std::size_t>(v + b) * width + u + a];
            if (a < kSurroundReach && usable(a + 1, b))
              steps.push_back(std::fabs(rho[static_cast<std::size_t>(v + b) * width + u + a + 1] - ra));
            if (b < kSurroundReach && usable(a, b + 1))
              steps.push_back(std::fabs(rho[static_cast<std::size_t>(v + b + 1) * width + u + a] - ra));
          }
        // The neighbours that lie on a surface themselves (next to a time-of-flight edge, half
        // of them may be mixed pixels too); none: the point stays, nothing tells where it belongs.
        int kept = 0;
        for (int dv = -1; dv <= 1; ++dv)
          for (int du = -1; du <= 1; ++du)
            if (usable(du, dv)) // the ring of the 5 x 5 test: valid and on a surface
              neighbours[kept++] = rho[static_cast<std::size_t>(v + dv) * width + u + du];
        if (kept == 0)
          continue;
        // A point within those steps of one of them is on their surface.
        if (!steps.empty()) {
          std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
          const float typical = kSurroundSteps * steps[steps.size() / 2];
          if (std::any_of(neighbours, neighbours + kept, [&](float q) { return std::fabs(q - r) <= typical; }))
            continue;
        }
        for (int a = 1; a < kept; ++a) // insertion sort of at most 8 values
          for (int b = a; b > 0 && neighbours[b] < neighbours[b - 1]; --b)
            std::swap(neighbours[b], neighbours[b - 1]);
        Candidate c{i, u, v, r, kept, {}};
        std::copy(neighbours, neighbours + kept, c.ring);
        rows[v].push_back(c);
      }
    }
  }
  // Where the ring's surface points lie on two sides of a depth edge (their nearest and farthest
  // more than the tolerance apart), the side is the one most points of the wider surroundings
  // are nearer to, outliers left out: next to a silhouette the ring holds a few pixels of each
  // side, and which side the point's pixel belongs to shows in the edge's course around it.
  std::vector<unsigned char> outlier(rho.size(), 0);
  for (const std::vector<Candidate>& row : rows)
    for (const Candidate& c : row)
      outlier[c.index] = 1;
  for (const std::vector<Candidate>& row : rows)
    for (const Candidate& c : row) {
      const float* ring = c.ring;
      int first = 0, last = c.kept; // the ring values of the chosen side: [first, last)
      const float low = ring[0], high = ring[c.kept - 1];
      if (high - low > toleranceAt(low)) {
        int nearer_low = 0, nearer_high = 0;
        const auto usableAt = [&](int a, int b) {
          return validAt(a, b) && !outlier[static_cast<std::size_t>(b) * width + a];
        };
        for (int b = -kSideReach; b <= kSideReach; ++b)
          for (int a = -kSideReach; a <= kSideReach; ++a) {
            // Pixels in point-symmetric pairs only: a hole on one side of the edge (a shadow)
            // takes its mirror image on the other out too.
            if ((a == 0 && b == 0) || !usableAt(c.u + a, c.v + b) || !usableAt(c.u - a, c.v - b))
              continue;
            const float q = rho[static_cast<std::size_t>(c.v + b) * width + c.u + a];
            (std::fabs(q - low) < std::fabs(q - high) ? nearer_low : nearer_high) += 1;
          }
        const int split = static_cast<int>(std::upper_bound(ring, ring + c.kept, 0.5f * (low + high)) - ring);
        if (nearer_low != nearer_high) {
          if (nearer_low > nearer_high)
            last = split;
          else
            first = split;
        }
      }
      // The median of that side; of two middle ones the one nearer the point (a mean of two could
      // fall between two surfaces).
      const float mid_low = ring[first + (last - first - 1) / 2], mid_high = ring[first + (last - first) / 2];
      found.push_back(IsolatedPoint{c.index, std::fabs(mid_low - c.range) <= std::fabs(mid_high - c.range) ? mid_low
                                                                                                            : mid_high});
    }
  return found;
}

} // namespace range_nlm
