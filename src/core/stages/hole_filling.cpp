// Stage::hole_filling (FilterParameters::fill_holes): holes filled from non-local candidates whose
// patches match the hole's border, each pixel on the depth level its row and column runs give it
// (docs/method.md, "Hole filling").
//
// Everything is computed in inverse depth w = 1 / (z - viewpoint z). On a plane seen by a pinhole
// camera w is an affine function of the pixel coordinates, so a patch of a plane shifted by t
// differs from the plane at the hole by a constant: comparing patches up to a constant offset
// (the depth-offset-invariant distance below) finds every patch of the hole's own surface, and
// the candidate's values plus that offset lie exactly on the surface at the hole. The noise of
// an active stereo camera is about constant in w, too.
#include "stages.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <numeric>

namespace range_nlm
{
namespace detail
{
namespace
{

/// Valid pixels within this many pixels (chessboard distance) of a hole are its border: two rings,
/// so that the border patch holds a little of the surface's shape, not just one line of pixels.
constexpr int kBorderRing = 2;
/// Border pixels split into depth levels where their sorted depths jump by more than this many
/// noise sigmas...
constexpr float kEdgeSigmas = 6.0f;
/// ... and more than this many pixel footprints (a surface seen at 76 degrees from its normal
/// steps by 4 footprints from pixel to pixel). A split on one surface only costs border pixels:
/// the candidates still carry the surface's shape.
constexpr float kEdgeFootprints = 4.0f;
/// A depth level with fewer border pixels is taken for stray points (flying pixels, outliers),
/// not a surface to fill from.
constexpr int kMinLevelPixels = 4;
/// The best candidates (smallest patch distance) whose values are combined per hole pixel.
constexpr int kCandidates = 16;
/// Candidate values farther than this many noise sigmas from the pixel's weighted median are
/// left out of its mean: a minority of candidates that see another surface where the hole is
/// cannot pull the fill between levels.
constexpr float kKeepSigmas = 3.0f;
/// Relative margin of the candidate search's early stop over the rounding of the distances.
constexpr double kScatterMargin = 1e-4;
/// The search window's half side: this many pixels around the hole, plus twice its width.
constexpr int kMinReach = 6;

/// A connected region of invalid pixels.
struct Hole
{
  std::vector<int> pixels;
  int u0 = 0, v0 = 0, u1 = 0, v1 = 0; // bounding box, inclusive
  bool touches_border = false;
  int width = 0;
};

/// The 8-connected regions of invalid pixels of `grid`, in the order of their first pixel in
/// row-major order.
std::vector<Hole>
findHoles(const Grid& grid)
{
  const int w = grid.width, h = grid.height;
  std::vector<int> label(grid.size(), -1);
  std::vector<Hole> holes;
  std::deque<int> queue;
  for (int start = 0; start < static_cast<int>(grid.size()); ++start) {
    if (grid.valid[start] || label[start] >= 0)
      continue;
    Hole hole;
    hole.u0 = hole.u1 = start % w;
    hole.v0 = hole.v1 = start / w;
    const int id = static_cast<int>(holes.size());
    label[start] = id;
    queue.push_back(start);
    while (!queue.empty()) {
      const int i = queue.front();
      queue.pop_front();
      hole.pixels.push_back(i);
      const int u = i % w, v = i / w;
      hole.u0 = std::min(hole.u0, u), hole.u1 = std::max(hole.u1, u);
      hole.v0 = std::min(hole.v0, v), hole.v1 = std::max(hole.v1, v);
      hole.touches_border = hole.touches_border || u == 0 || v == 0 || u == w - 1 || v == h - 1;
      for (int dv = -1; dv <= 1; ++dv)
        for (int du = -1; du <= 1; ++du) {
          const int uu = u + du, vv = v + dv;
          if (uu < 0 || vv < 0 || uu >= w || vv >= h)
            continue;
          const int j = vv * w + uu;
          if (!grid.valid[j] && label[j] < 0) {
            label[j] = id;
            queue.push_back(j);
          }
        }
    }
    std::sort(hole.pixels.begin(), hole.pixels.end());
    holes.push_back(std::move(hole));
  }
  return holes;
}

/// Sets each hole's width: the largest, over its pixels, of the shorter of the pixel's run of
/// invalid pixels along its row and along its column. A long, thin shadow is as wide as it is
/// thin; a filled pixel is never farther than half the width from the border along a row or a
/// column.
void
measureWidths(const Grid& grid, std::vector<Hole>& holes)
{
  const int w = grid.width, h = grid.height;
  std::vector<int> row_run(grid.size(), 0), column_run(grid.size(), 0);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w;) {
      int end = u;
      while (end < w && !grid.valid[v * w + end])
        ++end;
      for (int k = u; k < end; ++k)
        row_run[v * w + k] = end - u;
      u = std::max(end, u + 1);
    }
  for (int u = 0; u < w; ++u)
    for (int v = 0; v < h;) {
      int end = v;
      while (end < h && !grid.valid[end * w + u])
        ++end;
      for (int k = v; k < end; ++k)
        column_run[k * w + u] = end - v;
      v = std::max(end, v + 1);
    }
  for (Hole& hole : holes)
    for (int i : hole.pixels)
      hole.width = std::max(hole.width, std::min(row_run[i], column_run[i]));
}

/// What the fill of every hole reads: the frame before any hole was filled, its inverse depths
/// (0 where invalid or not in front of the viewpoint) and its noise profile.
struct FillFrame
{
  const Grid& grid;
  /// The frame as given: its points lie on their pixels' rays (the filter may have moved the
  /// output's along their normals).
  const Grid& input;
  const Viewpoint& viewpoint;
  std::vector<float> w;
  NoiseProfile profile;
  /// The output's per-point uncertainty (FilterParameters::uncertainty), metres; empty when off.
  /// The fills read it at measured points and write it at filled ones.
  std::vector<float>& uncertainty;
};

/// The hole's pixel rays (x - vx, y - vy) / (z - vz) as affine functions of the pixel
/// coordinates, fitted to its border: exact for a pinhole camera (a function of u and of v),
/// close for any smooth projection over a hole's extent.
struct RayModel
{
  double x[3] = {0, 0, 0}, y[3] = {0, 0, 0};
  float rx(int u, int v) const { return static_cast<float>(x[0] + x[1] * u + x[2] * v); }
  float ry(int u, int v) const { return static_cast<float>(y[0] + y[1] * u + y[2] * v); }
  /// Angle between neighbouring pixels' rays, about: the pixel footprint per unit depth.
  float pitch() const { return static_cast<float>(std::max(std::abs(x[1]), std::abs(y[2]))); }
};

/// Solves the 3 x 3 system a x = b (Cramer's rule); false if it is (nearly) singular.
bool
solve3(const double a[3][3], const double b[3], double x[3])
{
  const auto det = [](const double m[3][3]) {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  };
  const double d = det(a);
  if (!(std::abs(d) > 1e-9))
    return false;
  for (int c = 0; c < 3; ++c) {
    double m[3][3];
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k)
        m[r][k] = k == c ? b[r] : a[r][k];
    x[c] = det(m) / d;
  }
  return true;
}

/// The least-squares RayModel of the border pixels; false if they do not span the plane of the
/// image (or one lies behind the viewpoint).
bool
fitRays(const FillFrame& f, const std::vector<int>& border, RayModel& rays)
{
  const Grid& g = f.input;
  double a[3][3] = {}, bx[3] = {}, by[3] = {};
  for (int i : border) {
    const double depth = double(g.z[i]) - f.viewpoint[2];
    if (!(depth > 0.0))
      return false;
    const double c[3] = {1.0, double(i % g.width), double(i / g.width)};
    const double rx = (double(g.x[i]) - f.viewpoint[0]) / depth, ry = (double(g.y[i]) - f.viewpoint[1]) / depth;
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k)
        a[r][k] += c[r] * c[k];
      bx[r] += c[r] * rx;
      by[r] += c[r] * ry;
    }
  }
  return border.size() >= 3 && solve3(a, bx, rays.x) && solve3(a, by, rays.y);
}

/// The border of a piece of a hole: the valid pixels within kBorderRing pixels of it.
std::vector<int>
borderOf(const Grid& g, const Hole& piece)
{
  const int u0 = std::max(0, piece.u0 - kBorderRing), u1 = std::min(g.width - 1, piece.u1 + kBorderRing);
  const int v0 = std::max(0, piece.v0 - kBorderRing), v1 = std::min(g.height - 1, piece.v1 + kBorderRing);
  const int w = u1 - u0 + 1;
  // The piece dilated by the ring, on the box around it.
  std::vector<unsigned char> near(static_cast<std::size_t>(w) * (v1 - v0 + 1), 0);
  for (int i : piece.pixels) {
    const int u = i % g.width, v = i / g.width;
    for (int vv = std::max(v0, v - kBorderRing); vv <= std::min(v1, v + kBorderRing); ++vv)
      for (int uu = std::max(u0, u - kBorderRing); uu <= std::min(u1, u + kBorderRing); ++uu)
        near[static_cast<std::size_t>(vv - v0) * w + (uu - u0)] = 1;
  }
  std::vector<int> border;
  for (int v = v0; v <= v1; ++v)
    for (int u = u0; u <= u1; ++u)
      if (near[static_cast<std::size_t>(v - v0) * w + (u - u0)] && g.valid[v * g.width + u])
        border.push_back(v * g.width + u);
  return border;
}

/// A hole cut into square tiles of side max(8, 2 width + 4) where its extent is longer than that
/// (a shadow along a whole silhouette): each piece is matched and filled on its own, with the
/// border around it, so that a long hole needs no candidate as long as itself.
std::vector<Hole>
piecesOf(const Grid& g, const Hole& hole)
{
  const int tile = std::max(8, 2 * hole.width + 4);
  if (hole.u1 - hole.u0 < tile && hole.v1 - hole.v0 < tile)
    return {hole};
  std::vector<std::pair<long, int>> keyed; // (tile index, pixel)
  const long columns = g.width / tile + 1;
  for (int i : hole.pixels)
    keyed.emplace_back((i / g.width) / tile * columns + (i % g.width) / tile, i);
  std::sort(keyed.begin(), keyed.end());
  std::vector<Hole> pieces;
  for (std::size_t k = 0; k < keyed.size(); ++k) {
    if (k == 0 || keyed[k].first != keyed[k - 1].first) {
      pieces.emplace_back();
      pieces.back().width = hole.width;
      pieces.back().u0 = pieces.back().v0 = std::numeric_limits<int>::max();
      pieces.back().u1 = pieces.back().v1 = std::numeric_limits<int>::min();
    }
    Hole& piece = pieces.back();
    const int i = keyed[k].second, u = i % g.width, v = i / g.width;
    piece.pixels.push_back(i);
    piece.u0 = std::min(piece.u0, u), piece.u1 = std::max(piece.u1, u);
    piece.v0 = std::min(piece.v0, v), piece.v1 = std::max(piece.v1, v);
  }
  return pieces;
}

/// The noise sigma of inverse depth at border pixel i: the profile's sigma at its range, at least
/// a ten-thousandth of the depth, divided by depth^2 (dw = dz / z^2).
float
inverseDepthSigma(const FillFrame& f, int i)
{
  const Grid& g = f.grid;
  const float dx = g.x[i] - f.viewpoint[0], dy = g.y[i] - f.viewpoint[1], dz = g.z[i] - f.viewpoint[2];
  const float rho = std::sqrt(dx * dx + dy * dy + dz * dz);
  const float sigma = std::max(f.profile.empty() ? 0.0f : f.profile.sigmaAt(rho), 1e-4f * dz);
  return sigma / (dz * dz);
}

/// A depth level of the pixels around a hole: its pixels (sorted) and the edge threshold in
/// inverse depth at its median.
struct Level
{
  std::vector<int> pixels;
  float threshold = 0.0f;
  bool holds(int i) const { return std::binary_search(pixels.begin(), pixels.end(), i); }
};

/// The depth levels of `around` (valid pixels), farthest first: split where their sorted inverse
/// depths jump by more than the edge threshold; levels of fewer than kMinLevelPixels pixels are
/// stray points and left out.
std::vector<Level>
splitLevels(const FillFrame& f, std::vector<int> around, const RayModel& rays)
{
  // Farthest first: the smallest inverse depth.
  std::sort(around.begin(), around.end(), [&](int a, int b) { return f.w[a] < f.w[b] || (f.w[a] == f.w[b] && a < b); });
  const auto edge = [&](int i) {
    const float depth = 1.0f / f.w[i];
    return std::max(kEdgeSigmas * inverseDepthSigma(f, i), kEdgeFootprints * rays.pitch() / depth);
  };
  std::vector<Level> levels;
  for (std::size_t begin = 0, end = 0; begin < around.size(); begin = end) {
    end = begin + 1;
    while (end < around.size() && f.w[around[end]] - f.w[around[end - 1]] <= edge(around[end]))
      ++end;
    if (end - begin < static_cast<std::size_t>(kMinLevelPixels))
      continue;
    Level level;
    level.pixels.assign(around.begin() + begin, around.begin() + end);
    level.threshold = edge(level.pixels[level.pixels.size() / 2]);
    std::sort(level.pixels.begin(), level.pixels.end());
    levels.push_back(std::move(level));
  }
  return levels;
}

/// The first valid pixel from hole pixel i in steps of (du, dv), or -1 at the frame's edge;
/// `steps` is how many steps it took.
int
endOfRun(const Grid& g, int i, int du, int dv, int& steps)
{
  int u = i % g.width, v = i / g.width;
  for (steps = 1;; ++steps) {
    u += du, v += dv;
    if (u < 0 || v < 0 || u >= g.width || v >= g.height)
      return -1;
    if (g.valid[v * g.width + u])
      return v * g.width + u;
  }
}

/// The ends of the runs of invalid pixels through each pixel of `piece` along its row and its
/// column: (left, right, up, down) per pixel, -1 at the frame's edge, and each run's length.
struct RunEnds
{
  std::vector<std::array<int, 4>> ends;
  std::vector<std::array<int, 2>> lengths; // row, column
};

RunEnds
runEndsOf(const Grid& g, const Hole& piece)
{
  RunEnds r;
  for (int i : piece.pixels) {
    int left = 0, right = 0, up = 0, down = 0;
    std::array<int, 4> e{endOfRun(g, i, -1, 0, left), endOfRun(g, i, 1, 0, right), endOfRun(g, i, 0, -1, up),
                         endOfRun(g, i, 0, 1, down)};
    r.ends.push_back(e);
    r.lengths.push_back({left + right - 1, up + down - 1});
  }
  return r;
}

/// The level each pixel of the piece is filled from (an index into `levels`, -1 for none), from
/// the levels at the ends of its row and column runs. A run whose two ends lie on one level spans
/// the hole on that surface: the surface goes on under the hole (a dark patch on a foreground
/// object, also where it reaches the object's silhouette). Without one, the farther end of the
/// shorter run: the hole lies on the occluded side of a depth edge, as a shadow beside a
/// foreground does. The shorter run is the more local evidence; of two spanning runs too. An end
/// on no level (a stray point, or farther from the piece than aroundOf reaches) counts for nothing.
std::vector<int>
assignLevels(const RunEnds& runs, const std::vector<Level>& levels)
{
  const auto levelOf = [&](int i) {
    if (i < 0)
      return -1;
    for (std::size_t k = 0; k < levels.size(); ++k)
      if (levels[k].holds(i))
        return static_cast<int>(k);
    return -1; // a stray point
  };
  std::vector<int> assigned(runs.ends.size(), -1);
  for (std::size_t p = 0; p < runs.ends.size(); ++p) {
    int spanning = -1, spanning_length = 0, open = -1, open_length = 0;
    for (int run = 0; run < 2; ++run) {
      const int a = levelOf(runs.ends[p][2 * run]), b = levelOf(runs.ends[p][2 * run + 1]);
      const int length = runs.lengths[p][run];
      if (a >= 0 && a == b) {
        if (spanning < 0 || length < spanning_length)
          spanning = a, spanning_length = length;
      } else if (a >= 0 || b >= 0) {
        // Levels are farthest first: the smaller index of the ends present.
        const int farther = a < 0 ? b : (b < 0 ? a : std::min(a, b));
        if (open < 0 || length < open_length)
          open = farther, open_length = length;
      }
    }
    assigned[p] = spanning >= 0 ? spanning : open;
  }
  return assigned;
}

/// One candidate: the shift t of the hole's patch, its distance and the offset that carries its
/// values to the hole's level.
struct Candidate
{
  float distance;
  float offset;
  int du, dv;
};

/// The hole's patch: its border level (`known`) and its pixels (`unknown`), as offsets from the
/// hole's first pixel, and the pairs of 4-neighbours within it along rows and along columns,
/// which must not straddle a depth edge in a candidate.
struct Patch
{
  std::vector<int> known, unknown;
  std::vector<std::pair<int, int>> row_pairs, column_pairs;
  /// The level's inverse depth per pixel along a row and along a column (its least-squares
  /// plane): a slanted surface (a floor seen from low) steps by this much from pixel to pixel
  /// without an edge.
  float step_u = 0.0f, step_v = 0.0f;
  int u0, v0, u1, v1; // extent of the patch, frame coordinates
};

/// The least-squares plane w = a + b u + c v of the inverse depths of `pixels`: (b, c), exact on a
/// plane seen by a pinhole camera; zero if the pixels do not span the image plane.
void
inverseDepthSteps(const FillFrame& f, const std::vector<int>& pixels, float& step_u, float& step_v)
{
  const int width = f.grid.width;
  double a[3][3] = {}, b[3] = {}, x[3] = {0.0, 0.0, 0.0};
  for (int i : pixels) {
    const double c[3] = {1.0, double(i % width), double(i / width)};
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k)
        a[r][k] += c[r] * c[k];
      b[r] += c[r] * f.w[i];
    }
  }
  if (!solve3(a, b, x))
    x[1] = x[2] = 0.0;
  step_u = static_cast<float>(x[1]);
  step_v = static_cast<float>(x[2]);
}

Patch
makePatch(const FillFrame& f, const std::vector<int>& unknown, const std::vector<int>& level)
{
  const Grid& g = f.grid;
  Patch p;
  p.known = level;
  p.unknown = unknown;
  inverseDepthSteps(f, level, p.step_u, p.step_v);
  p.u0 = p.v0 = std::numeric_limits<int>::max();
  p.u1 = p.v1 = std::numeric_limits<int>::min();
  std::vector<int> all = level;
  all.insert(all.end(), unknown.begin(), unknown.end());
  std::sort(all.begin(), all.end());
  for (int i : all) {
    const int u = i % g.width, v = i / g.width;
    p.u0 = std::min(p.u0, u), p.u1 = std::max(p.u1, u), p.v0 = std::min(p.v0, v), p.v1 = std::max(p.v1, v);
    if (u + 1 < g.width && std::binary_search(all.begin(), all.end(), i + 1))
      p.row_pairs.emplace_back(i, i + 1);
    if (std::binary_search(all.begin(), all.end(), i + g.width))
      p.column_pairs.emplace_back(i, i + g.width);
  }
  return p;
}

/// Whether the patch shifted by `shift` straddles a depth edge: 4-neighbours whose inverse depths
/// differ from the level's step by more than `threshold`.
bool
straddlesEdge(const FillFrame& f, const Patch& p, int shift, float threshold)
{
  for (const auto& pair : p.row_pairs)
    if (std::abs(f.w[pair.second + shift] - f.w[pair.first + shift] - p.step_u) > threshold)
      return true;
  for (const auto& pair : p.column_pairs)
    if (std::abs(f.w[pair.second + shift] - f.w[pair.first + shift] - p.step_v) > threshold)
      return true;
  return false;
}

/// The kCandidates shifts within `reach` pixels whose patch, wholly valid and without a depth
/// edge (straddlesEdge), is nearest the hole's
/// border level up to a constant: distance = mean over the level of (d - mean d)^2 with
/// d = w(k) - w(k + t). Sorted by distance, then by shift (deterministic).
std::vector<Candidate>
searchCandidates(const FillFrame& f, const Patch& p, int reach, float threshold)
{
  const Grid& g = f.grid;
  std::vector<Candidate> best;
  const float n = static_cast<float>(p.known.size());
  const auto better = [](const Candidate& a, const Candidate& b) {
    return a.distance < b.distance || (a.distance == b.distance && (a.dv < b.dv || (a.dv == b.dv && a.du < b.du)));
  };
  for (int dv = -reach; dv <= reach; ++dv)
    for (int du = -reach; du <= reach; ++du) {
      if ((du == 0 && dv == 0) || p.u0 + du < 0 || p.v0 + dv < 0 || p.u1 + du >= g.width || p.v1 + dv >= g.height)
        continue;
      const int shift = dv * g.width + du;
      bool usable = true;
      for (std::size_t k = 0; k < p.unknown.size() && usable; ++k)
        usable = f.w[p.unknown[k] + shift] > 0.0f;
      // Once kCandidates are kept, a shift stops as soon as the scatter of the differences so far
      // (a lower bound of n times the distance: sum (d - mean)^2 over all pixels is at least that
      // over the first k about their own mean) shows it cannot be kept; the margin keeps every
      // shift the whole sum would keep, whatever the rounding.
      const double bound = best.size() == static_cast<std::size_t>(kCandidates)
                               ? n * double(best.back().distance) * (1.0 + kScatterMargin) + 1e-12
                               : std::numeric_limits<double>::infinity();
      double sum = 0.0, sum2 = 0.0;
      for (std::size_t k = 0; k < p.known.size() && usable; ++k) {
        const float c = f.w[p.known[k] + shift];
        usable = c > 0.0f;
        const double d = double(f.w[p.known[k]]) - c;
        sum += d, sum2 += d * d;
        if ((k & 15) == 15 && sum2 - sum * sum / double(k + 1) > bound)
          usable = false;
      }
      if (!usable)
        continue;
      const double mean = sum / n;
      const Candidate c{static_cast<float>(std::max(0.0, sum2 / n - mean * mean)), static_cast<float>(mean), du, dv};
      if (best.size() == static_cast<std::size_t>(kCandidates) && !better(c, best.back()))
        continue;
      if (straddlesEdge(f, p, shift, threshold))
        continue;
      best.insert(std::upper_bound(best.begin(), best.end(), c, better), c);
      if (best.size() > static_cast<std::size_t>(kCandidates))
        best.pop_back();
    }
  return best;
}

/// A filled pixel's inverse depth, and what its candidates say about it: the weighted variance
/// of the values taken and the weighted mean of their own uncertainty (metres; 0 when off).
struct Fill
{
  float w = 0.0f;
  float variance = 0.0f;
  float shared = 0.0f;
};

/// The inverse depth of hole pixel i from the candidates: their values carried to the hole's
/// level, weighted by exp(-(distance - best distance) / (2 sigma^2)); the weighted mean of those
/// within kKeepSigmas sigmas of their weighted median.
Fill
combine(const FillFrame& f, const std::vector<Candidate>& candidates, int i, float sigma)
{
  struct Value
  {
    float value, weight;
    int at; // the candidate's pixel
    bool operator<(const Value& o) const { return value < o.value || (value == o.value && at < o.at); }
  };
  std::vector<Value> values;
  const float h2 = 2.0f * sigma * sigma;
  for (const Candidate& c : candidates) {
    const int at = i + c.dv * f.grid.width + c.du;
    values.push_back({f.w[at] + c.offset, std::exp(-(c.distance - candidates.front().distance) / h2), at});
  }
  std::sort(values.begin(), values.end());
  float total = 0.0f;
  for (const auto& v : values)
    total += v.weight;
  float below = 0.0f, median = values.back().value;
  for (const auto& v : values) {
    below += v.weight;
    if (below >= 0.5f * total) {
      median = v.value;
      break;
    }
  }
  double sum = 0.0, sum2 = 0.0, weight = 0.0, shared = 0.0;
  const bool uncertain = !f.uncertainty.empty();
  for (const auto& v : values)
    if (std::abs(v.value - median) <= kKeepSigmas * sigma) {
      sum += double(v.value) * v.weight, sum2 += double(v.value) * v.value * v.weight, weight += v.weight;
      if (uncertain && std::isfinite(f.uncertainty[v.at]))
        shared += double(f.uncertainty[v.at]) * v.weight;
    }
  Fill out;
  const double mean = sum / weight;
  out.w = static_cast<float>(mean);
  out.variance = static_cast<float>(std::max(0.0, sum2 / weight - mean * mean));
  out.shared = static_cast<float>(shared / weight);
  return out;
}

/// The pixels around a piece that its levels are split from: its border ring and the ends of its
/// runs that lie within width + kBorderRing pixels of its box (a tile cut from a long hole sees
/// the surfaces beside the tiles next to it; the far ends of a long shadow's column runs are left
/// out, so that a patch stays as small as the hole is wide).
std::vector<int>
aroundOf(const Grid& g, const Hole& piece, const RunEnds& runs, std::vector<int> around)
{
  const int reach = piece.width + kBorderRing;
  for (const auto& ends : runs.ends)
    for (int i : ends) {
      if (i < 0)
        continue; // the frame's edge
      const int u = i % g.width, v = i / g.width;
      if (u >= piece.u0 - reach && u <= piece.u1 + reach && v >= piece.v0 - reach && v <= piece.v1 + reach)
        around.push_back(i);
    }
  std::sort(around.begin(), around.end());
  around.erase(std::unique(around.begin(), around.end()), around.end());
  return around;
}

/// Fills `pixels` (of a piece as wide as `width`) from the candidates whose patches match
/// `level`, into `out` (marking `filled`); leaves them holes where no candidate was found.
void
fillFromLevel(const FillFrame& f, const std::vector<int>& pixels, const Level& level, int width, const RayModel& rays,
              const std::vector<unsigned char>& active, Grid& out, std::vector<unsigned char>& filled)
{
  const Grid& g = f.grid;
  std::vector<float> sigmas;
  for (int i : level.pixels)
    sigmas.push_back(inverseDepthSigma(f, i));
  std::nth_element(sigmas.begin(), sigmas.begin() + sigmas.size() / 2, sigmas.end());
  const float sigma = sigmas[sigmas.size() / 2];
  const Patch patch = makePatch(f, pixels, level.pixels);
  const std::vector<Candidate> candidates = searchCandidates(f, patch, kMinReach + 2 * width, level.threshold);
  if (candidates.empty())
    return;
  for (int i : pixels) {
    if (!active.empty() && !active[i])
      continue;
    const Fill fill = combine(f, candidates, i, sigma);
    const float w = fill.w;
    if (!(w > 0.0f) || !std::isfinite(1.0f / w))
      continue;
    const float depth = 1.0f / w;
    const int u = i % g.width, v = i / g.width;
    out.x[i] = f.viewpoint[0] + rays.rx(u, v) * depth;
    out.y[i] = f.viewpoint[1] + rays.ry(u, v) * depth;
    out.z[i] = f.viewpoint[2] + depth;
    out.valid[i] = 1;
    filled[i] = 1;
    if (!f.uncertainty.empty()) {
      // Along the ray, metres: the candidates' disagreement (dz = dw / w^2) and the error they
      // share, at most the mean of their own (as for a pass over filtered points).
      const float spread = std::sqrt(fill.variance) * depth * depth;
      f.uncertainty[i] = std::sqrt(spread * spread + fill.shared * fill.shared);
    }
  }
}

/// Fills one hole (or piece of one) into `out` (marking `filled`): each pixel from the level
/// assignLevels gives it, each level's pixels from their own candidates; pixels without a level
/// or a candidate stay holes.
void
fillHole(const FillFrame& f, const Hole& hole, const std::vector<unsigned char>& active, Grid& out,
         std::vector<unsigned char>& filled)
{
  const Grid& g = f.grid;
  const std::vector<int> border = borderOf(g, hole);
  RayModel rays;
  if (!fitRays(f, border, rays))
    return;
  const RunEnds runs = runEndsOf(g, hole);
  const std::vector<Level> levels = splitLevels(f, aroundOf(g, hole, runs, border), rays);
  const std::vector<int> assigned = assignLevels(runs, levels);
  for (std::size_t k = 0; k < levels.size(); ++k) {
    std::vector<int> pixels;
    for (std::size_t p = 0; p < hole.pixels.size(); ++p)
      if (assigned[p] == static_cast<int>(k))
        pixels.push_back(hole.pixels[p]);
    if (!pixels.empty())
      fillFromLevel(f, pixels, levels[k], hole.width, rays, active, out, filled);
  }
}

} // namespace

void
fillHoles(const Grid& input, const FilterParameters& parameters, const Viewpoint& viewpoint,
          const std::vector<unsigned char>& active, Workspace& workspace)
{
  Grid& out = workspace.run.output;
  workspace.run.filled.assign(out.size(), 0);
  std::vector<Hole> holes = findHoles(out);
  measureWidths(out, holes);
  std::vector<Hole> pieces;
  for (const Hole& hole : holes)
    if (!hole.touches_border && hole.width <= parameters.fill_holes)
      for (Hole& piece : piecesOf(out, hole))
        pieces.push_back(std::move(piece));
  if (pieces.empty())
    return;
  const int threads = resolveThreads(parameters.threads);
  // The fills read the frame as it was before any hole was filled, so that their order (and the
  // thread count) does not matter: a copy, since they write into the output.
  const Grid before = out;
  FillFrame frame{before, input, viewpoint, std::vector<float>(out.size(), 0.0f), {}, workspace.run.uncertainty};
  for (std::size_t i = 0; i < before.size(); ++i)
    if (before.valid[i] && before.z[i] - viewpoint[2] > 0.0f)
      frame.w[i] = 1.0f / (before.z[i] - viewpoint[2]);
  try {
    // `input` is the current frame as the call was given it: its profile is known once estimated.
    frame.profile = currentFrameProfile(input, parameters, viewpoint, workspace);
  } catch (const std::invalid_argument&) {
    // Too few points for a profile: the thresholds fall back to their floors.
  }
  const std::ptrdiff_t count = static_cast<std::ptrdiff_t>(pieces.size());
  std::vector<unsigned char>& filled = workspace.run.filled;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (std::ptrdiff_t k = 0; k < count; ++k)
    fillHole(frame, pieces[k], active, out, filled);
}

} // namespace detail
} // namespace range_nlm
