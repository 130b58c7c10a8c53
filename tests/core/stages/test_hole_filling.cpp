// The hole filling (src/core/stages/hole_filling.cpp): holes in a plane end on the plane, a hole
// on a depth step takes one side and is never bridged, the width limit and the frame border,
// nothing changes when it is off, the same result for any thread count, filled points' uncertainty.
#include "../frame_fixtures.h"

#include <range_nlm/parameters.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <random>

using namespace range_nlm;
using namespace range_nlm::test;

namespace
{
constexpr int kWidth = 64, kHeight = 48;
constexpr float kFocal = 52.5f; // 525 pixels at 640 columns
constexpr float kCx = 0.5f * (kWidth - 1), kCy = 0.5f * (kHeight - 1);

/// A pinhole frame whose pixel (u, v) lies at depth z = depth(u, v) on its ray, with independent
/// depth noise of `sigma` metres.
Grid
frameOf(const std::function<float(int, int)>& depth, float sigma, unsigned seed = 3)
{
  Grid g(kWidth, kHeight);
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, sigma);
  for (int v = 0; v < kHeight; ++v)
    for (int u = 0; u < kWidth; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * kWidth + u;
      const float z = depth(u, v) + noise(rng);
      g.x[i] = (u - kCx) / kFocal * z;
      g.y[i] = (v - kCy) / kFocal * z;
      g.z[i] = z;
    }
  g.updateValidity();
  return g;
}

/// Depth on the ray of (u, v) of the plane through (0, 0, 1.5) with normal (0.3, -0.2, -1): a
/// plane tilted against the image, so that its depth is not affine in the pixel coordinates.
float
tiltedPlane(int u, int v)
{
  const float rx = (u - kCx) / kFocal, ry = (v - kCy) / kFocal;
  return 1.5f / (1.0f - 0.3f * rx + 0.2f * ry);
}

/// Makes the pixels [u0, u1) x [v0, v1) invalid.
void
punch(Grid& g, int u0, int v0, int u1, int v1)
{
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = v0; v < v1; ++v)
    for (int u = u0; u < u1; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * g.width + u;
      g.x[i] = g.y[i] = g.z[i] = nan;
    }
  g.updateValidity();
}

/// The default with windows for a frame of a few dozen pixels, filling holes up to `max_width`.
FilterParameters
filling(int max_width)
{
  FilterParameters p;
  p.search_window = 7;
  p.normal_window = 5;
  p.normal_presmooth_window = 5;
  p.fill_holes = max_width;
  p.threads = 1;
  return p;
}

FilterRun
run(const Grid& frame, const FilterParameters& p)
{
  return runFilter({&frame}, 0, p, kOrigin, {});
}

std::size_t
countFilled(const FilterRun& r)
{
  std::size_t n = 0;
  for (unsigned char f : r.filled)
    n += f;
  return n;
}

/// Expects every pixel of [u0, u1) x [v0, v1) filled, at depth(u, v) within absolute + relative
/// times that depth.
void
expectFilledAt(const FilterRun& r, int u0, int v0, int u1, int v1, const std::function<float(int, int)>& depth,
               float absolute, float relative = 0.0f)
{
  for (int v = v0; v < v1; ++v)
    for (int u = u0; u < u1; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * kWidth + u;
      ASSERT_TRUE(r.filled[i]) << u << ", " << v;
      EXPECT_NEAR(r.output.z[i], depth(u, v), absolute + relative * depth(u, v)) << u << ", " << v;
    }
}
} // namespace

TEST(HoleFilling, AHoleInAPlaneEndsOnThePlaneOnItsPixelsRays)
{
  Grid frame = frameOf(tiltedPlane, 0.001f);
  punch(frame, 28, 20, 34, 26); // 6 x 6
  const FilterRun r = run(frame, filling(8));
  ASSERT_EQ(r.filled.size(), frame.size());
  EXPECT_EQ(countFilled(r), 36u);
  for (int v = 20; v < 26; ++v)
    for (int u = 28; u < 34; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * kWidth + u;
      ASSERT_TRUE(r.filled[i] && r.output.valid[i]) << u << ", " << v;
      // Within 2 noise sigmas of the true plane (the candidates' mean is far less noisy than that).
      EXPECT_NEAR(r.output.z[i], tiltedPlane(u, v), 0.002f) << u << ", " << v;
      EXPECT_NEAR(r.output.x[i] / r.output.z[i], (u - kCx) / kFocal, 1e-5f);
      EXPECT_NEAR(r.output.y[i] / r.output.z[i], (v - kCy) / kFocal, 1e-5f);
    }
}

TEST(HoleFillingDepthStep, AHoleAcrossAStraightStepTakesEachSideWhereTheStepGoesOn)
{
  // Near plane at 1.0 m left of column 32, far plane at 1.6 m right of it; the hole straddles
  // the step. Above and below the hole each side goes on: its columns span the hole on their own
  // side, so each pixel takes the side of its column, and nothing lies between.
  Grid frame = frameOf([](int u, int) { return u < 32 ? 1.0f : 1.6f; }, 0.001f);
  punch(frame, 29, 18, 35, 26);
  expectFilledAt(run(frame, filling(8)), 29, 18, 35, 26, [](int u, int) { return u < 32 ? 1.0f : 1.6f; }, 0.005f);
}

TEST(HoleFillingDepthStep, AShadowTakesTheSurfaceBehindItRowByRow)
{
  // A foreground at 1.0 m right of column 32 casts a shadow 6 pixels wide on its left; behind
  // the shadow a wall at 2.0 m above row 24 and a box at 1.5 m below it. Each row of the shadow
  // lies on the surface left of it, never on the foreground: the shadow is on the occluded side.
  Grid frame = frameOf([](int u, int v) { return u >= 32 ? 1.0f : (v < 24 ? 2.0f : 1.5f); }, 0.001f);
  punch(frame, 26, 10, 32, 39);
  expectFilledAt(run(frame, filling(8)), 26, 10, 32, 39, [](int, int v) { return v < 24 ? 2.0f : 1.5f; }, 0.01f);
}

TEST(HoleFillingDepthStep, ADarkPatchReachingAForegroundsSilhouetteStaysOnTheForeground)
{
  // A foreground at 1.0 m left of column 32 before a background at 1.6 m; the hole lies on the
  // foreground and reaches its silhouette. Its columns span it on the foreground.
  Grid frame = frameOf([](int u, int) { return u < 32 ? 1.0f : 1.6f; }, 0.001f);
  punch(frame, 27, 20, 32, 27);
  expectFilledAt(run(frame, filling(8)), 27, 20, 32, 27, [](int, int) { return 1.0f; }, 0.005f);
}

TEST(HoleFilling, AHoleInAFloorSeenFromLowIsFilledOnTheFloor)
{
  // A floor 0.1 m below the camera (a wall at 3 m above the horizon): from row to row its inverse
  // depth steps by more than a depth edge's threshold (4 pixel footprints), a slant and no edge.
  const auto floor = [](int, int v) { return v < 26 ? 3.0f : 0.1f * kFocal / (v - kCy); };
  Grid frame = frameOf(floor, 0.0005f);
  punch(frame, 20, 30, 25, 34);
  expectFilledAt(run(frame, filling(8)), 20, 30, 25, 34, floor, 0.0f, 0.01f);
}

TEST(HoleFillingDepthStep, AHoleBetweenTwoLevelsIsNeverGivenARangeBetweenThem)
{
  // A diagonal step: each hole pixel must end on one of the two levels, whatever side it takes.
  Grid frame = frameOf([](int u, int v) { return u + v < 56 ? 1.2f : 2.0f; }, 0.002f, 9);
  punch(frame, 25, 22, 32, 28);
  const FilterRun r = run(frame, filling(8));
  for (std::size_t i = 0; i < frame.size(); ++i)
    if (r.filled[i]) {
      const float z = r.output.z[i];
      EXPECT_TRUE(std::abs(z - 1.2f) < 0.01f || std::abs(z - 2.0f) < 0.015f) << i << ": " << z;
    }
  EXPECT_GT(countFilled(r), 0u);
}

TEST(HoleFilling, OffLeavesTheOutputAsItWasAndMarksNothing)
{
  Grid frame = frameOf(tiltedPlane, 0.001f);
  punch(frame, 28, 20, 33, 25);
  const FilterRun off = run(frame, filling(0));
  EXPECT_TRUE(off.filled.empty());
  const FilterRun on = run(frame, filling(8));
  // The fill touches only the hole: every other point is the bits the filter gave without it.
  Grid unfilled = on.output;
  for (std::size_t i = 0; i < frame.size(); ++i)
    if (on.filled[i]) {
      EXPECT_FALSE(frame.valid[i]);
      unfilled.x[i] = unfilled.y[i] = unfilled.z[i] = std::numeric_limits<float>::quiet_NaN();
      unfilled.valid[i] = 0;
    }
  EXPECT_TRUE(sameBits(unfilled, off.output));
  EXPECT_EQ(countFilled(on), 25u);
}

TEST(HoleFilling, HolesWiderThanTheLimitOrOnTheFrameBorderStayHoles)
{
  Grid frame = frameOf(tiltedPlane, 0.001f);
  punch(frame, 10, 10, 17, 17); // 7 x 7: 7 wide
  punch(frame, 40, 8, 42, 40);  // 2 x 32: 2 wide, long as a shadow
  punch(frame, 0, 30, 4, 34);   // touches the left border
  const auto filledIn = [](const FilterRun& r, int u0, int v0, int u1, int v1) {
    std::size_t n = 0;
    for (int v = v0; v < v1; ++v)
      for (int u = u0; u < u1; ++u)
        n += r.filled[static_cast<std::size_t>(v) * kWidth + u];
    return n;
  };
  const FilterRun six = run(frame, filling(6));
  EXPECT_EQ(filledIn(six, 10, 10, 17, 17), 0u);
  EXPECT_EQ(filledIn(six, 40, 8, 42, 40), 64u);
  EXPECT_EQ(filledIn(six, 0, 30, 4, 34), 0u);
  for (std::size_t i = 0; i < frame.size(); ++i)
    if (!six.filled[i] && !frame.valid[i])
      EXPECT_FALSE(six.output.valid[i]) << i;
  const FilterRun seven = run(frame, filling(7));
  EXPECT_EQ(filledIn(seven, 10, 10, 17, 17), 49u);
  EXPECT_EQ(filledIn(seven, 0, 30, 4, 34), 0u);
}

TEST(HoleFilling, TheSameForOneTwoAndThreeThreads)
{
  Grid frame = frameOf([](int u, int v) { return u < 30 ? tiltedPlane(u, v) - 0.4f : tiltedPlane(u, v); }, 0.002f);
  punch(frame, 27, 10, 33, 16);
  punch(frame, 8, 30, 12, 36);
  punch(frame, 45, 25, 47, 44);
  FilterParameters p = filling(6);
  p.threads = 1;
  p.uncertainty = true;
  const FilterRun one = run(frame, p);
  EXPECT_GT(countFilled(one), 0u);
  for (int threads : {2, 3}) {
    p.threads = threads;
    const FilterRun other = run(frame, p);
    EXPECT_TRUE(sameBits(one.output, other.output)) << threads;
    EXPECT_EQ(one.filled, other.filled) << threads;
    ASSERT_EQ(one.uncertainty.size(), other.uncertainty.size());
    EXPECT_EQ(std::memcmp(one.uncertainty.data(), other.uncertainty.data(), one.uncertainty.size() * sizeof(float)), 0)
        << threads;
  }
}

TEST(HoleFilling, FilledPointsCarryTheUncertaintyOfTheirCandidates)
{
  Grid frame = frameOf(tiltedPlane, 0.001f);
  punch(frame, 28, 20, 34, 26);
  FilterParameters p = filling(8);
  p.uncertainty = true;
  const FilterRun r = run(frame, p);
  ASSERT_EQ(r.uncertainty.size(), frame.size());
  float lowest = std::numeric_limits<float>::infinity(), highest = 0.0f;
  for (std::size_t i = 0; i < frame.size(); ++i)
    if (frame.valid[i] && std::isfinite(r.uncertainty[i]))
      lowest = std::min(lowest, r.uncertainty[i]), highest = std::max(highest, r.uncertainty[i]);
  std::size_t filled = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (!r.filled[i])
      continue;
    ++filled;
    const float u = r.uncertainty[i];
    ASSERT_TRUE(std::isfinite(u)) << i;
    // At least what the candidates share (the least of the measured points' own), and on a plane
    // the candidates agree: not far above the most uncertain measured point.
    EXPECT_GE(u, lowest) << i;
    EXPECT_LE(u, 2.0f * highest) << i;
    // And it covers the fill's error (along the ray, the depth's).
    const int column = static_cast<int>(i % kWidth), row = static_cast<int>(i / kWidth);
    EXPECT_LE(std::abs(r.output.z[i] - tiltedPlane(column, row)), 3.0f * u) << i;
  }
  EXPECT_EQ(filled, 36u);
  // Without the uncertainty nothing is written for it.
  EXPECT_TRUE(run(frame, filling(8)).uncertainty.empty());
}
