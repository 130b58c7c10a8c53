// The parts of the isolated-outlier step (detail::findIsolatedPoints), shared by their
// translation units and by the tests (not installed): the surface test (which points agree with
// their neighbours and lie on a surface), the candidates (which points are isolated, with the
// ranges they may move to) and the side vote (which side of a depth edge a candidate takes).
#pragma once

#include "internal.h"
#include "tuned.h"

#include <algorithm>
#include <cstddef>
#include <vector>

namespace range_nlm
{
namespace detail
{
/// What the parts of the isolated-outlier step share: the frame's ranges and the tolerance of
/// agreement between points.
struct OutlierFrame
{
  /// The range of every point of the grid; 0 marks a point the test leaves alone and does not
  /// compare with: invalid, at the viewpoint, or so far that its range overflows.
  const std::vector<float>& rho;
  int width, height;
  /// Noise sigmas of the test (FilterParameters::outlier_sigmas) and the frame's noise profile.
  float sigmas;
  const NoiseProfile& profile;
  /// The angle between adjacent rays (medianRayAngle).
  float ray_angle;

  /// Whether pixel (u, v) is in the frame and holds a point the test compares with.
  bool validAt(int u, int v) const
  {
    return u >= 0 && v >= 0 && u < width && v < height && rho[static_cast<std::size_t>(v) * width + u] > 0.0f;
  }
  /// The tolerance of agreement at range r: `sigmas` noise sigmas, at least tuned::kFootprints
  /// pixel footprints (range x the angle between adjacent rays).
  float toleranceAt(float r) const
  {
    return std::max(sigmas * profile.sigmaAt(r), tuned::kFootprints * ray_angle * r);
  }
};

/// The angle between adjacent rays: the median of |p_i - p_j| / rho_i over adjacent valid pixels
/// at every 4th column of every 8th row (on a surface facing the sensor, the pixel's angular
/// size); 0 if there is none. By `threads` threads, with the same result.
float
medianRayAngle(const Grid& grid, const std::vector<float>& rho, int threads);

/// Whether point (a, b) lies on a surface: it agrees with two valid 8-neighbours other than pixel
/// (skip_a, skip_b), or with one that agrees in turn with one of its own neighbours other than
/// (a, b). A point agrees with a neighbour within the tolerance at its range of the neighbour's
/// range, or of the straight continuation of the line from the pixel beyond the neighbour.
bool
onSurface(const OutlierFrame& frame, int a, int b, int skip_a, int skip_b);

/// A point that lies on no surface and is far from the surface points around it: the isolated
/// outlier's candidate.
struct OutlierCandidate
{
  std::size_t index;
  int u, v;
  float range;
  int kept;      // how many of ring[] are set
  float ring[8]; // the ranges of its 8-neighbours on a surface, ascending
};

/// The candidates among the points with `active` set (every point if empty), per row in column
/// order, by `threads` threads with the same result. The surroundings whose range steps guard a
/// candidate are the adjacent pairs (right and down neighbours) within tuned::kSurroundReach
/// pixels of it (5 x 5), and a candidate must be farther than tuned::kSurroundSteps times their
/// median step from every neighbour on a surface.
std::vector<std::vector<OutlierCandidate>>
findOutlierCandidates(const Grid& grid, const OutlierFrame& frame, const std::vector<unsigned char>& active,
                      int threads);

/// Each candidate with the range it moves to, in the order of `rows`: the median of its ring, or,
/// where the ring lies on two sides of a depth edge, of the side most of its surroundings within
/// tuned::kSideReach pixels (11 x 11) are nearer to.
std::vector<IsolatedPoint>
voteSides(const OutlierFrame& frame, const std::vector<std::vector<OutlierCandidate>>& rows);

} // namespace detail
} // namespace range_nlm
