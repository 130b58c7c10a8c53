// The multiscale run (src/core/stages/multiscale.cpp): the scales it uses, holes and odd sizes,
// depth steps, thread counts, the direct evaluation as reference, and what it is for (noise
// correlated over many pixels).
#include "../frame_fixtures.h"
#include "core/stages/multiscale.h"
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

TEST(Multiscale, ReductionTakesOneSideOfADepthStep)
{
  // A 2 x 2 block whose left column is at 1.0 m and right column at 1.1 m: its coarse point lies
  // on one of the two surfaces (the lower-median range's), never between them.
  const Grid fine = depthStep(2, 2, 1.0f, 1.1f, 0.0f);
  const NoiseProfile profile{{1.0f}, {0.001f}, {0.01f}};
  const detail::SurfaceTolerance tolerance{profile, 0.001f};
  std::vector<float> rho;
  std::vector<unsigned char> member;
  Grid coarse;
  detail::reduceFrame(fine, kOrigin, tolerance, 1, rho, coarse, &member);
  ASSERT_EQ(coarse.width, 1);
  ASSERT_EQ(coarse.height, 1);
  ASSERT_TRUE(coarse.valid[0]);
  EXPECT_FLOAT_EQ(coarse.z[0], 1.0f);
  EXPECT_EQ(member, (std::vector<unsigned char>{1, 0, 1, 0}));
}

TEST(Multiscale, ReductionOfOddSizesAndHoles)
{
  Grid fine = depthStep(5, 3, 1.0f, 1.0f, 0.0f);
  for (std::size_t i : {0u, 1u, 5u, 6u}) { // the whole first block
    fine.valid[i] = 0;
    fine.x[i] = fine.y[i] = fine.z[i] = std::nanf("");
  }
  const NoiseProfile profile{{1.0f}, {0.001f}, {0.01f}};
  const detail::SurfaceTolerance tolerance{profile, 0.001f};
  std::vector<float> rho;
  Grid coarse;
  detail::reduceFrame(fine, kOrigin, tolerance, 1, rho, coarse, nullptr);
  ASSERT_EQ(coarse.width, 3);
  ASSERT_EQ(coarse.height, 2);
  EXPECT_FALSE(coarse.valid[0]);
  EXPECT_TRUE(std::isnan(coarse.z[0]));
  // The last column and row are blocks of their own: the mean of the pixels they hold.
  EXPECT_FLOAT_EQ(coarse.x[2], fine.x[4]);
  EXPECT_FLOAT_EQ(coarse.x[5], fine.x[14]);
  for (std::size_t c = 1; c < coarse.size(); ++c)
    EXPECT_TRUE(coarse.valid[c]) << c;
}

TEST(Multiscale, CarriedCorrectionsNeverCrossADepthStep)
{
  // Fine columns 0-1 at 1.0 m, 2-3 at 1.1 m; the coarse points of the two sides move +10 mm and
  // -50 mm. Every fine point moves by its own side's correction alone, along its ray.
  const Grid fine = depthStep(4, 2, 1.0f, 1.1f, 0.0f);
  std::vector<float> fine_rho;
  detail::rangesOf(fine, kOrigin, 1, fine_rho);
  const NoiseProfile profile{{1.0f}, {0.001f}, {0.01f}};
  const detail::SurfaceTolerance tolerance{profile, 0.001f};
  const std::vector<float> coarse_rho{fine_rho[0], fine_rho[3]}, correction{0.01f, -0.05f};
  const std::vector<unsigned char> member(8, 1);
  const detail::CarrySource source{2, 1, coarse_rho, correction, member, tolerance};
  Grid out;
  detail::carryCorrections(fine, fine_rho, source, kOrigin, {}, 1, out);
  std::vector<float> out_rho;
  detail::rangesOf(out, kOrigin, 1, out_rho);
  for (int i = 0; i < 8; ++i) {
    const float expected = fine_rho[i] + (i % 4 < 2 ? 0.01f : -0.05f);
    EXPECT_NEAR(out_rho[i], expected, 1e-6f) << i;
    // Along its ray: the direction from the viewpoint is kept.
    EXPECT_NEAR(out.x[i] / out_rho[i], fine.x[i] / fine_rho[i], 1e-6f) << i;
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
  EXPECT_LT(pyramid, 0.9 * single) << "raw " << raw << ", one scale " << single;
}
