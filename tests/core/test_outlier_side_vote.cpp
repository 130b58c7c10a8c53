// The side vote of the isolated-outlier step: the range a point between two surfaces moves to.
#include "outlier_fixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace range_nlm;
using namespace range_nlm::test;

TEST(Outliers, AMixedPixelBetweenTwoSurfacesGoesToOneOfThemNotBetween)
{
  // A step edge in the noisy plane: columns < 160 half a metre nearer; a pixel of the far
  // side's first column moved to 5 cm behind the halfway point (a mixed pixel), its
  // 8-neighbours 3 near and 5 far.
  Grid g = stepEdge();
  const int w = g.width;
  const NoiseProfile profile = profileOf(g);
  const std::size_t mixed = static_cast<std::size_t>(100) * w + 160;
  const float far = rangeOf(g, mixed);
  pushAlongRay(g, mixed, -0.2f); // 5 cm behind the halfway point: nearer the far surface
  Grid out = g;
  EXPECT_EQ(detail::correctIsolatedPoints(out, profile, 10.0f, kOrigin, {}, 1), 1u);
  // The median of 3 near and 5 far neighbours: the far surface, within its noise.
  EXPECT_NEAR(rangeOf(out, mixed), far, 0.02f);
  // With the neighbours left, right, above and below removed, 2 near and 2 far (diagonal)
  // neighbours remain: of the two middle values, the one nearer the point (far), not their mean.
  Grid even = g;
  for (std::size_t j : {mixed - w, mixed + w, mixed - 1, mixed + 1})
    even.valid[j] = 0;
  Grid out_even = even;
  EXPECT_EQ(detail::correctIsolatedPoints(out_even, profile, 10.0f, kOrigin, {}, 1), 1u);
  const float r = rangeOf(out_even, mixed);
  EXPECT_TRUE(std::fabs(r - far) < 0.02f) << "moved to " << r << " m, between the surfaces";
}

TEST(Outliers, AMixedPixelTakesTheSideOfTheEdgeMostOfItsSurroundingsAreOn)
{
  // The step edge again (columns < 160 half a metre nearer) and a mixed pixel halfway in the far
  // side's first column, with the three pixels right of it missing: its ring holds 3 near and
  // 2 far points, whose median is the near surface, but the 11 x 11 surroundings are mostly far
  // (the edge runs straight past the pixel, which is on the far side of it).
  Grid g = stepEdge();
  const int w = g.width;
  const NoiseProfile profile = profileOf(g);
  const std::size_t mixed = static_cast<std::size_t>(100) * w + 160;
  const float far = rangeOf(g, mixed);
  pushAlongRay(g, mixed, -0.25f);
  for (std::size_t j : {mixed - w + 1, mixed + 1, mixed + w + 1})
    g.valid[j] = 0;
  Grid out = g;
  EXPECT_EQ(detail::correctIsolatedPoints(out, profile, 10.0f, kOrigin, {}, 1), 1u);
  EXPECT_NEAR(rangeOf(out, mixed), far, 0.02f);
}
