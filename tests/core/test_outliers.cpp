// Isolated outliers (correctIsolatedPoints, FilterParameters::outlier_sigmas): which points are
// moved, where to, and which are left alone.
#include "core/internal.h"

#include <range_nlm/core/pipeline.h>
#include <range_nlm/eval/synthetic_scene.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

using namespace range_nlm;

namespace
{
const Viewpoint kOrigin{0.0f, 0.0f, 0.0f};

Grid
gridOf(const pcl::PointCloud<pcl::PointXYZ>& c)
{
  return Grid::fromInterleaved(reinterpret_cast<const float*>(c.points.data()), static_cast<int>(c.width),
                               static_cast<int>(c.height), sizeof(pcl::PointXYZ) / sizeof(float));
}

/// A plane 1.5 m in front of a 320 x 240 camera with Kinect-like noise (about 4 mm there).
Grid
noisyPlane()
{
  SceneOptions o;
  o.width = 320;
  o.height = 240;
  o.fx = o.fy = 525.0 * 320 / 640;
  o.scene = SceneType::plane;
  o.plane_depth = 1.5;
  o.noise = noiseModelFromString("kinect");
  o.seed = 5;
  return gridOf(renderSequence(o).front().noisy);
}

float
rangeOf(const Grid& g, std::size_t i)
{
  return std::sqrt(g.x[i] * g.x[i] + g.y[i] * g.y[i] + g.z[i] * g.z[i]);
}

/// Moves point i along its ray by `delta` (metres of range).
void
pushAlongRay(Grid& g, std::size_t i, float delta)
{
  const float f = (rangeOf(g, i) + delta) / rangeOf(g, i);
  g.x[i] *= f, g.y[i] *= f, g.z[i] *= f;
}

/// The noisy plane with a step edge: columns < 160 half a metre nearer.
Grid
stepEdge()
{
  Grid g = noisyPlane();
  for (int v = 0; v < g.height; ++v)
    for (int u = 0; u < 160; ++u)
      pushAlongRay(g, static_cast<std::size_t>(v) * g.width + u, -0.5f);
  return g;
}

NoiseProfile
profileOf(const Grid& g)
{
  return detail::estimateNoiseProfile(g, 9, 1000, 42, kOrigin, 1);
}

bool
samePoint(const Grid& a, const Grid& b, std::size_t i)
{
  return a.valid[i] == b.valid[i] && std::memcmp(&a.x[i], &b.x[i], sizeof(float)) == 0 &&
         std::memcmp(&a.y[i], &b.y[i], sizeof(float)) == 0 && std::memcmp(&a.z[i], &b.z[i], sizeof(float)) == 0;
}
} // namespace

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
