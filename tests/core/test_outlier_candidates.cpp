// The candidates of the isolated-outlier step: which points are isolated, with the ranges of their
// surface neighbours, and the guard of their surroundings' range steps.
#include "outlier_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <vector>

using namespace range_nlm;
using namespace range_nlm::test;

namespace
{
/// The candidates of g (tolerance 10 mm, adjacent rays 1 / 500 rad apart), all rows in order.
std::vector<detail::OutlierCandidate>
candidatesOf(const Grid& g, const std::vector<unsigned char>& active, int threads)
{
  const std::vector<float> rho = rangesOf(g);
  const NoiseProfile profile = flatProfile();
  const detail::OutlierFrame frame{rho, g.width, g.height, 10.0f, profile, 1.0f / kFocal};
  const auto rows = detail::findOutlierCandidates(g, frame, active, threads);
  EXPECT_EQ(rows.size(), static_cast<std::size_t>(g.height));
  std::vector<detail::OutlierCandidate> all;
  for (const auto& row : rows)
    all.insert(all.end(), row.begin(), row.end());
  return all;
}
} // namespace

// A point 80 mm off a noise-free plane is its only candidate, with its range and the ranges of
// its 8 neighbours (all on the plane) in ascending order, for any thread count; inactive, it is
// none.
TEST(Outliers, AnIsolatedPointIsTheOnlyCandidateWithItsNeighboursRangesAscending)
{
  const int w = 21, h = 17, u = 10, v = 8;
  Grid g = gridAtDepth(w, h, [](int, int) { return 1.0f; });
  const std::size_t spike = static_cast<std::size_t>(v) * w + u;
  pushAlongRay(g, spike, 0.08f);
  const std::vector<detail::OutlierCandidate> found = candidatesOf(g, {}, 1);
  ASSERT_EQ(found.size(), 1u);
  const detail::OutlierCandidate& c = found[0];
  EXPECT_EQ(c.index, spike);
  EXPECT_EQ(c.u, u);
  EXPECT_EQ(c.v, v);
  EXPECT_EQ(c.range, rangeOf(g, spike));
  ASSERT_EQ(c.kept, 8);
  std::vector<float> ring;
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du)
      if (du != 0 || dv != 0)
        ring.push_back(rangeOf(g, static_cast<std::size_t>(v + dv) * w + u + du));
  std::sort(ring.begin(), ring.end());
  EXPECT_TRUE(std::equal(ring.begin(), ring.end(), c.ring));
  const std::vector<detail::OutlierCandidate> again = candidatesOf(g, {}, 3);
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(std::memcmp(&again[0], &c, sizeof(c)), 0);
  std::vector<unsigned char> active(g.size(), 1);
  active[spike] = 0;
  EXPECT_TRUE(candidatesOf(g, active, 1).empty());
}

// A surface steep to the rays, 50 mm farther with each row: its points agree with the straight
// continuation of their column and lie on it. A point halfway between two rows' ranges (25 mm
// off, beyond the 10 mm tolerance) lies on no surface, but it is within 4 times the median range
// step of its 5 x 5 surroundings (50 mm) of its neighbours: no candidate. The same point on a
// flat plane, whose steps are tiny, is one.
TEST(Outliers, SurroundingsWithLargeRangeStepsKeepTheirPoints)
{
  const int w = 21, h = 17, u = 10, v = 8;
  const std::size_t i = static_cast<std::size_t>(v) * w + u;
  Grid steep = gridAtDepth(w, h, [](int, int row) { return 1.0f + 0.05f * row; });
  pushAlongRay(steep, i, 0.025f);
  const std::vector<float> rho = rangesOf(steep);
  const NoiseProfile profile = flatProfile();
  const detail::OutlierFrame frame{rho, w, h, 10.0f, profile, 1.0f / kFocal};
  ASSERT_FALSE(detail::onSurface(frame, u, v, -1, -1));
  EXPECT_TRUE(detail::onSurface(frame, u, v - 1, -1, -1));
  EXPECT_TRUE(candidatesOf(steep, {}, 1).empty());

  Grid flat = gridAtDepth(w, h, [](int, int) { return 1.0f; });
  pushAlongRay(flat, i, 0.025f);
  const std::vector<detail::OutlierCandidate> found = candidatesOf(flat, {}, 1);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].index, i);
}
