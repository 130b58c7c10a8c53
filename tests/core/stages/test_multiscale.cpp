// The multiscale run (src/core/stages/multiscale.cpp): the scales it uses, holes and odd sizes,
// depth steps, thread counts, the direct evaluation as reference, and what it is for (noise
// correlated over many pixels).
#include "../frame_fixtures.h"
#include "core/stages/stages.h"

#include <range_nlm/parameters.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>

using namespace range_nlm;
using namespace range_nlm::test;

namespace
{
/// Multiscale parameters whose windows fit frames of a few dozen pixels.
FilterParameters
multiscale(int scales)
{
  FilterParameters p;
  p.scales = scales;
  p.search_window = 5;
  p.normal_window = 5;
  p.normal_presmooth_window = 5;
  return p;
}

Grid
filtered(const Grid& frame, const FilterParameters& p)
{
  return runFilter({&frame}, 0, p, kOrigin, {}).output;
}

/// Two planes facing the camera, at `near` metres left of the middle column and `far` right of
/// it, with independent range noise of `sigma` metres.
Grid
depthStep(int width, int height, float near, float far, float sigma)
{
  Grid g;
  g.width = width;
  g.height = height;
  const std::size_t n = static_cast<std::size_t>(width) * height;
  g.x.resize(n);
  g.y.resize(n);
  g.z.resize(n);
  g.valid.assign(n, 1);
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(0.0f, sigma);
  const float f = 525.0f * width / 640.0f;
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * width + u;
      const float z = (u < width / 2 ? near : far) + noise(rng);
      g.x[i] = (u - 0.5f * (width - 1)) / f * z;
      g.y[i] = (v - 0.5f * (height - 1)) / f * z;
      g.z[i] = z;
    }
  return g;
}

bool
sameBits(const std::vector<float>& a, const std::vector<float>& b)
{
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

/// RMS of the output's distance to the plane scene's truth along the truth normals, metres.
double
planeRmse(const Grid& out, const pcl::PointCloud<pcl::PointNormal>& truth)
{
  double sum = 0.0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    const pcl::PointNormal& t = truth.points[i];
    if (!out.valid[i] || !std::isfinite(t.z))
      continue;
    const double d = (out.x[i] - t.x) * t.normal_x + (out.y[i] - t.y) * t.normal_y + (out.z[i] - t.z) * t.normal_z;
    sum += d * d;
    ++count;
  }
  return std::sqrt(sum / count);
}
} // namespace

TEST(Multiscale, UsesFewerScalesWhereTheCoarsestWouldBeNarrowerThanTheWindows)
{
  Grid g = depthStep(40, 30, 1.0f, 1.0f, 0.0f);
  FilterParameters p = multiscale(6);
  // 40 x 30 -> 20 x 15 -> 10 x 8 -> 5 x 4: the 5 x 5 windows fit down to 10 x 8.
  EXPECT_EQ(detail::usableScales(g, p), 3);
  p.scales = 2;
  EXPECT_EQ(detail::usableScales(g, p), 2);
  p.scales = 1;
  EXPECT_EQ(detail::usableScales(g, p), 1);
  p = multiscale(6);
  p.search_window = 17;
  EXPECT_EQ(detail::usableScales(g, p), 1);
}

TEST(Multiscale, ScalesOutsideOneToSixAreRejectedByName)
{
  FilterParameters p;
  for (int scales : {0, 7, -1}) {
    p.scales = scales;
    try {
      p.validate();
      ADD_FAILURE() << scales;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("scales = " + std::to_string(scales)), std::string::npos) << e.what();
    }
  }
}

TEST(Multiscale, HolesStayHolesInFramesOfOddSize)
{
  SceneOptions o = planeScene("stereo", 101, 77);
  o.dropout = 0.2;
  const Grid noisy = gridOf(renderSequence(o).front().noisy);
  const Grid out = filtered(noisy, multiscale(3));
  ASSERT_EQ(out.width, 101);
  ASSERT_EQ(out.height, 77);
  std::size_t moved = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    ASSERT_EQ(out.valid[i], noisy.valid[i]) << i;
    if (!noisy.valid[i]) {
      EXPECT_TRUE(std::isnan(out.x[i]) && std::isnan(out.y[i]) && std::isnan(out.z[i])) << i;
      continue;
    }
    ASSERT_TRUE(std::isfinite(out.x[i]) && std::isfinite(out.y[i]) && std::isfinite(out.z[i])) << i;
    moved += out.z[i] != noisy.z[i];
  }
  EXPECT_GT(moved, noisy.countValid() * 9 / 10);
}

TEST(Multiscale, NeverBridgesADepthStep)
{
  // 2 x 2 blocks across the step take one side, and corrections are carried only within a side:
  // no point ends between the planes, and both sides keep their depth.
  const float sigma = 0.002f;
  const Grid noisy = depthStep(96, 64, 1.0f, 1.1f, sigma);
  const Grid out = filtered(noisy, multiscale(3));
  for (int v = 0; v < out.height; ++v)
    for (int u = 0; u < out.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * out.width + u;
      const float plane = u < out.width / 2 ? 1.0f : 1.1f;
      ASSERT_NEAR(out.z[i], plane, 6 * sigma) << u << ", " << v;
    }
}

TEST(Multiscale, IdenticalForOneTwoAndThreeThreads)
{
  SceneOptions o = planeScene("stereo", 160, 120);
  o.scene = SceneType::boxes;
  o.dropout = 0.05;
  const Grid noisy = gridOf(renderSequence(o).front().noisy);
  FilterParameters p = multiscale(3);
  p.threads = 1;
  const Grid one = filtered(noisy, p);
  for (int threads : {2, 3}) {
    p.threads = threads;
    const Grid other = filtered(noisy, p);
    EXPECT_TRUE(sameBits(one.x, other.x) && sameBits(one.y, other.y) && sameBits(one.z, other.z)) << threads;
  }
}

TEST(Multiscale, FastEvaluationMatchesTheDirectReference)
{
  SceneOptions o = planeScene("stereo", 128, 96);
  o.scene = SceneType::boxes;
  o.dropout = 0.05;
  const Grid noisy = gridOf(renderSequence(o).front().noisy);
  FilterParameters p = multiscale(3);
  const Grid fast = filtered(noisy, p);
  p.evaluation = Evaluation::direct;
  const Grid direct = filtered(noisy, p);
  double sum = 0.0, moved = 0.0;
  for (std::size_t i = 0; i < noisy.size(); ++i)
    if (noisy.valid[i]) {
      const double d = fast.z[i] - direct.z[i], m = direct.z[i] - noisy.z[i];
      sum += d * d;
      moved += m * m;
    }
  // The two evaluations differ by float rounding only: far below the filter's own moves.
  EXPECT_LT(std::sqrt(sum), 1e-3 * std::sqrt(moved));
}

TEST(Multiscale, RemovesNoiseCorrelatedOverManyPixelsBetterThanOneScale)
{
  SceneOptions o = planeScene("stereo", 320, 240);
  o.stereo_correlated_share = 0.9;
  o.stereo_correlation_length = 8.0;
  const SyntheticFrame frame = renderSequence(o).front();
  const Grid noisy = gridOf(frame.noisy);
  FilterParameters one;
  one.dilation = 1;
  FilterParameters three = one;
  three.scales = 3;
  const double raw = planeRmse(noisy, frame.truth);
  const double single = planeRmse(filtered(noisy, one), frame.truth);
  const double pyramid = planeRmse(filtered(noisy, three), frame.truth);
  EXPECT_LT(pyramid, 0.75 * single) << "raw " << raw << ", one scale " << single;
}
