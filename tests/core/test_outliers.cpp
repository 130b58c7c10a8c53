// Isolated outliers (correctIsolatedPoints, FilterParameters::outlier_sigmas): which points are
// moved, where to, and which are left alone.
#include "outlier_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace range_nlm;
using namespace range_nlm::test;

TEST(Outliers, ASpikeLandsOnItsNeighboursSurfaceAndNothingElseMoves)
{
  const Grid plane = noisyPlane();
  const NoiseProfile profile = profileOf(plane);
  Grid spiky = plane;
  const int w = plane.width;
  const std::vector<std::size_t> spikes{static_cast<std::size_t>(40) * w + 50, static_cast<std::size_t>(120) * w + 160,
                                        static_cast<std::size_t>(200) * w + 300};
  pushAlongRay(spiky, spikes[0], -0.5f); // a mismatch toward the sensor
  pushAlongRay(spiky, spikes[1], 0.3f);  // and away from it
  pushAlongRay(spiky, spikes[2], -0.2f);
  Grid one = spiky, two = spiky;
  EXPECT_EQ(detail::correctIsolatedPoints(one, profile, 10.0f, kOrigin, {}, 1), spikes.size());
  EXPECT_EQ(detail::correctIsolatedPoints(two, profile, 10.0f, kOrigin, {}, 2), spikes.size());
  for (std::size_t i = 0; i < plane.size(); ++i) {
    ASSERT_TRUE(samePoint(one, two, i)) << "thread count changed point " << i;
    if (std::find(spikes.begin(), spikes.end(), i) == spikes.end())
      ASSERT_TRUE(samePoint(one, spiky, i)) << "point " << i << " is no outlier but moved";
  }
  for (std::size_t i : spikes) {
    // Back on the plane to within the noise (the median of its neighbours), on its own ray.
    EXPECT_NEAR(rangeOf(one, i), rangeOf(plane, i), 0.02f);
    EXPECT_NEAR(one.x[i] / one.z[i], plane.x[i] / plane.z[i], 1e-5f);
    EXPECT_NEAR(one.y[i] / one.z[i], plane.y[i] / plane.z[i], 1e-5f);
  }
  // Noise alone is no outlier at 10 sigmas: the noisy plane keeps every point.
  Grid clean = plane;
  EXPECT_EQ(detail::correctIsolatedPoints(clean, profile, 10.0f, kOrigin, {}, 1), 0u);
  // Off with 0 sigmas or without a profile.
  Grid off = spiky;
  EXPECT_EQ(detail::correctIsolatedPoints(off, profile, 0.0f, kOrigin, {}, 1), 0u);
  EXPECT_EQ(correctIsolatedPoints(off, NoiseProfile{}, 10.0f, kOrigin), 0u);
  for (std::size_t i = 0; i < plane.size(); ++i)
    ASSERT_TRUE(samePoint(off, spiky, i));
}

TEST(Outliers, ThinStructuresSteepSurfacesLonePointsHolesAndInactivePointsStay)
{
  const Grid plane = noisyPlane();
  const NoiseProfile profile = profileOf(plane);
  const int w = plane.width, h = plane.height;
  Grid g = plane;
  // A wire one pixel wide, 0.4 m in front of the plane: every point of it agrees with the
  // points above and below it.
  for (int v = 20; v < 100; ++v)
    pushAlongRay(g, static_cast<std::size_t>(v) * w + 30, -0.4f);
  // A point with a single valid neighbour (a hole around it) and a lone point (none).
  for (int v = 140; v <= 146; ++v)
    for (int u = 100; u <= 106; ++u)
      g.valid[static_cast<std::size_t>(v) * w + u] = 0;
  const std::size_t lone = static_cast<std::size_t>(143) * w + 103;
  const std::size_t pair_a = static_cast<std::size_t>(141) * w + 101, pair_b = pair_a + 1;
  g.valid[lone] = g.valid[pair_a] = g.valid[pair_b] = 1;
  pushAlongRay(g, lone, -0.5f);
  pushAlongRay(g, pair_a, -0.5f);
  // A surface steep to the rays: range steps of 25 noise sigmas per row, along its rows flat.
  for (int v = 160; v < 220; ++v)
    for (int u = 150; u < 250; ++u)
      pushAlongRay(g, static_cast<std::size_t>(v) * w + u, 0.1f * (v - 160));
  // A spike on an inactive point.
  const std::size_t inactive = static_cast<std::size_t>(60) * w + 200;
  pushAlongRay(g, inactive, -0.5f);
  std::vector<unsigned char> active(g.size(), 1);
  active[inactive] = 0;
  Grid out = g;
  EXPECT_EQ(detail::correctIsolatedPoints(out, profile, 10.0f, kOrigin, active, 2), 0u);
  for (std::size_t i = 0; i < g.size(); ++i)
    ASSERT_TRUE(samePoint(out, g, i)) << "point " << i << " (row " << i / w << ", column " << i % w << ") moved";
  // Active, the spike is moved; invalid points stay invalid.
  Grid all = g;
  EXPECT_EQ(detail::correctIsolatedPoints(all, profile, 10.0f, kOrigin, {}, 2), 1u);
  EXPECT_NEAR(rangeOf(all, inactive), rangeOf(plane, inactive), 0.02f);
  for (std::size_t i = 0; i < g.size(); ++i)
    ASSERT_EQ(all.valid[i], g.valid[i]);
  (void)h;
}
