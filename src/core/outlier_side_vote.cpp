// The side vote of the isolated-outlier step: where a candidate's surface neighbours lie on two
// sides of a depth edge, the side most of its 11 x 11 surroundings are nearer to, counted in
// point-symmetric pairs; the range it moves to is the median of that side.
#include "outliers.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace range_nlm
{
namespace
{
/// The ring values of one side of a depth edge: [first, last) of a candidate's ring.
struct Side
{
  int first, last;
};

/// The Side that candidate c takes: its whole ring unless its nearest and farthest are more than
/// the tolerance apart and its surroundings are not split evenly between them. `outlier` marks the
/// candidates, which have no vote.
Side
chooseSide(const detail::OutlierFrame& frame, const std::vector<unsigned char>& outlier,
           const detail::OutlierCandidate& c)
{
  const float* ring = c.ring;
  Side side{0, c.kept};
  const float low = ring[0], high = ring[c.kept - 1];
  if (!(high - low > frame.toleranceAt(low)))
    return side;
  int nearer_low = 0, nearer_high = 0;
  const auto usableAt = [&](int a, int b) {
    return frame.validAt(a, b) && !outlier[static_cast<std::size_t>(b) * frame.width + a];
  };
  for (int b = -tuned::kSideReach; b <= tuned::kSideReach; ++b)
    for (int a = -tuned::kSideReach; a <= tuned::kSideReach; ++a) {
      // Pixels in point-symmetric pairs only: a hole on one side of the edge (a shadow) takes its
      // mirror image on the other out too.
      if ((a == 0 && b == 0) || !usableAt(c.u + a, c.v + b) || !usableAt(c.u - a, c.v - b))
        continue;
      const float q = frame.rho[static_cast<std::size_t>(c.v + b) * frame.width + c.u + a];
      (std::fabs(q - low) < std::fabs(q - high) ? nearer_low : nearer_high) += 1;
    }
  const int split = static_cast<int>(std::upper_bound(ring, ring + c.kept, 0.5f * (low + high)) - ring);
  if (nearer_low != nearer_high) {
    if (nearer_low > nearer_high)
      side.last = split;
    else
      side.first = split;
  }
  return side;
}
} // namespace

std::vector<detail::IsolatedPoint>
detail::voteSides(const OutlierFrame& frame, const std::vector<std::vector<OutlierCandidate>>& rows)
{
  // Where the ring's surface points lie on two sides of a depth edge (their nearest and farthest
  // more than the tolerance apart), the side is the one most points of the wider surroundings
  // are nearer to, outliers left out: next to a silhouette the ring holds a few pixels of each
  // side, and which side the point's pixel belongs to shows in the edge's course around it.
  std::vector<IsolatedPoint> found;
  std::vector<unsigned char> outlier(frame.rho.size(), 0);
  for (const std::vector<OutlierCandidate>& row : rows)
    for (const OutlierCandidate& c : row)
      outlier[c.index] = 1;
  for (const std::vector<OutlierCandidate>& row : rows)
    for (const OutlierCandidate& c : row) {
      const float* ring = c.ring;
      const auto [first, last] = chooseSide(frame, outlier, c);
      // The median of that side; of two middle ones the one nearer the point (a mean of two could
      // fall between two surfaces).
      const float mid_low = ring[first + (last - first - 1) / 2], mid_high = ring[first + (last - first) / 2];
      found.push_back(IsolatedPoint{c.index, std::fabs(mid_low - c.range) <= std::fabs(mid_high - c.range) ? mid_low
                                                                                                            : mid_high});
    }
  return found;
}

} // namespace range_nlm
