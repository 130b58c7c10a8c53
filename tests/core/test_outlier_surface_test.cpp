// The surface test of the isolated-outlier step: the angle between adjacent rays, which points
// lie on a surface, and the frames whose points all do.
#include "outlier_fixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

using namespace range_nlm;
using namespace range_nlm::test;

TEST(Outliers, ANoiseFreeFrameHasNone)
{
  // The boxes scene without noise: its silhouettes, the faces seen at grazing angles and the
  // sphere's limb step along the rays by far more than its (tiny) noise sigma, but by a few pixel
  // footprints at most; none of its points is an outlier.
  SceneOptions o;
  o.width = 320;
  o.height = 240;
  o.fx = o.fy = 525.0 * 320 / 640;
  o.noise = noiseModelFromString("kinect");
  o.noise_scale = 0.0;
  const Grid g = gridOf(renderSequence(o).front().noisy);
  EXPECT_EQ(detail::findIsolatedPoints(g, profileOf(g), 10.0f, kOrigin, {}, 2).size(), 0u);
}

TEST(Outliers, TwoMixedPixelsThatAgreeOnlyWithEachOtherAreNoSurface)
{
  // A step edge as above; two vertically adjacent pixels of the far side's first column both 25
  // cm in front of the far surface (two mixed pixels at the same fraction): each agrees with
  // the other and with nothing else, and both land on a surface. A third pixel on the next row
  // is put in line with one of them and the far point beyond it (2 rho_j - rho_j'), as mixed
  // pixels can be by chance: no surface either.
  Grid g = stepEdge();
  const int w = g.width;
  const NoiseProfile profile = profileOf(g);
  const std::size_t upper = static_cast<std::size_t>(100) * w + 160, lower = upper + w;
  const float far_upper = rangeOf(g, upper), far_lower = rangeOf(g, lower);
  pushAlongRay(g, upper, -0.25f);
  pushAlongRay(g, lower, far_upper - 0.25f - far_lower); // the same range as the upper one
  Grid out = g;
  EXPECT_EQ(detail::correctIsolatedPoints(out, profile, 10.0f, kOrigin, {}, 1), 2u);
  EXPECT_NEAR(rangeOf(out, upper), far_upper, 0.02f);
  EXPECT_NEAR(rangeOf(out, lower), far_lower, 0.02f);

  // In line by chance: on row 50, the near side's last pixel (159), a mixed pixel at 160 and one at
  // 161 with rho(161) = 2 rho(160) - rho(159).
  Grid line = stepEdge();
  const std::size_t a = static_cast<std::size_t>(50) * w + 159, b = a + 1, c = a + 2;
  const float far_b = rangeOf(line, b), far_c = rangeOf(line, c);
  pushAlongRay(line, b, -0.3f);                                           // 0.2 m behind the near surface
  pushAlongRay(line, c, 2.0f * rangeOf(line, b) - rangeOf(line, a) - far_c); // 0.4 m behind it, in line
  Grid out_line = line;
  EXPECT_EQ(detail::correctIsolatedPoints(out_line, profileOf(line), 10.0f, kOrigin, {}, 1), 2u);
  EXPECT_NEAR(rangeOf(out_line, b), far_b, 0.02f);
  EXPECT_NEAR(rangeOf(out_line, c), far_c, 0.02f);
}

TEST(Outliers, AWireOnePixelWideIsASurface)
{
  // A wire half a metre in front of the noisy plane: one pixel wide, 40 pixels long, horizontal
  // and diagonal. Each of its points agrees with the wire points beside it (its tips with one,
  // which agrees with the next): none is an outlier.
  Grid g = noisyPlane();
  const int w = g.width;
  const std::size_t diagonal_start = static_cast<std::size_t>(150) * w + 100;
  for (int k = 0; k < 40; ++k) {
    pushAlongRay(g, static_cast<std::size_t>(60) * w + 100 + k, -0.5f);
    pushAlongRay(g, diagonal_start + static_cast<std::size_t>(k) * (w + 1), -0.5f);
  }
  Grid out = g;
  EXPECT_EQ(detail::correctIsolatedPoints(out, profileOf(noisyPlane()), 10.0f, kOrigin, {}, 1), 0u);
}

// The tolerance's floor: on a noise-free plane facing the sensor, adjacent rays 1 / 500 rad apart
// give that angle (to within the obliquity of the off-centre rays); no valid point gives 0. On a
// rough scene of many rows the angles are gathered by the threads: the same median with 1, 2 or 3.
TEST(Outliers, TheRayAngleIsThePixelsAngularSize)
{
  const Grid g = gridAtDepth(41, 33, [](int, int) { return 1.0f; });
  EXPECT_NEAR(detail::medianRayAngle(g, rangesOf(g), 1), 1.0f / kFocal, 0.01f / kFocal);
  const Grid empty(41, 33);
  EXPECT_EQ(detail::medianRayAngle(empty, rangesOf(empty), 2), 0.0f);
  const Grid rough = gridAtDepth(97, 203, [](int u, int v) { return 1.0f + 0.05f * float((u * 7 + v * 13) % 11); });
  const float one = detail::medianRayAngle(rough, rangesOf(rough), 1);
  EXPECT_GT(one, 1.5f / kFocal); // the steps between neighbours, not the rays' spacing
  for (int threads : {2, 3})
    EXPECT_EQ(detail::medianRayAngle(rough, rangesOf(rough), threads), one) << threads << " threads";
}

// On a noise-free plane, tolerance 10 mm: a point pushed 80 mm along its ray agrees with none of
// its neighbours; a pair of them agree only with each other (no surface); a wire of five agrees
// along itself (a surface, its tips through their one neighbour); the plane's points, the border
// and corners included, lie on a surface.
TEST(Outliers, ASurfaceIsTwoAgreeingNeighboursOrOneThatAgreesInTurn)
{
  const int w = 21, h = 21;
  Grid g = gridAtDepth(w, h, [](int, int) { return 1.0f; });
  const auto at = [&](int u, int v) { return static_cast<std::size_t>(v) * w + u; };
  pushAlongRay(g, at(4, 4), 0.08f); // alone
  pushAlongRay(g, at(4, 14), 0.08f); // a pair
  pushAlongRay(g, at(5, 14), 0.08f);
  for (int u = 10; u < 15; ++u) // a wire
    pushAlongRay(g, at(u, 8), 0.08f);
  const std::vector<float> rho = rangesOf(g);
  const NoiseProfile profile = flatProfile();
  const detail::OutlierFrame frame{rho, w, h, 10.0f, profile, 1.0f / kFocal};
  EXPECT_FALSE(detail::onSurface(frame, 4, 4, -1, -1));
  EXPECT_FALSE(detail::onSurface(frame, 4, 14, -1, -1));
  EXPECT_FALSE(detail::onSurface(frame, 5, 14, -1, -1));
  for (int u = 10; u < 15; ++u)
    EXPECT_TRUE(detail::onSurface(frame, u, 8, -1, -1)) << u;
  // Without its inner neighbour a tip agrees with nothing.
  EXPECT_FALSE(detail::onSurface(frame, 10, 8, 11, 8));
  for (const auto& [u, v] : {std::pair{0, 0}, std::pair{20, 0}, std::pair{0, 20}, std::pair{7, 0}, std::pair{3, 4},
                             std::pair{17, 17}})
    EXPECT_TRUE(detail::onSurface(frame, u, v, -1, -1)) << u << ", " << v;
}
