// The noise profile: its vectorized interpolation and its estimate on several threads.
#include "frame_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

using namespace range_nlm;
using namespace range_nlm::test;

// The vectorized interpolation of the noise profile behind the per-point maps gives the bits of
// sigmaAt / extentAt at every range: below, above and on the bin centres, between them, at 0
// (invalid points), for profiles of 1 to 9 bins (ranges made strictly increasing, as
// estimateNoiseProfile leaves them), and for any count of points (blocks and their tails); in
// every instruction-set build this CPU runs, with one profile and with two in the same scan.
TEST(NoiseProfile, VectorizedInterpolationIsTheScalarOne)
{
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int bins = 0; bins <= 9; ++bins)
    for (int trial = 0; trial < 4; ++trial) {
      NoiseProfile profile;
      float rho = 0.3f + u(rng);
      for (int b = 0; b < bins; ++b) {
        profile.range.push_back(rho);
        profile.sigma.push_back(0.001f + 0.01f * u(rng));
        profile.extent.push_back(0.002f + 0.02f * u(rng));
        rho += trial == 3 ? 0.0f : 0.5f * u(rng); // trial 3: equal ranges
        if (b > 0)
          profile.range[b] = std::max(profile.range[b], std::nextafter(profile.range[b - 1], 1e30f));
      }
      std::vector<float> at;
      for (int i = 0; i < 700; ++i)
        at.push_back(5.0f * u(rng));
      at.push_back(0.0f);
      for (float r : profile.range) {
        at.push_back(r);
        at.push_back(std::nextafter(r, 0.0f));
        at.push_back(std::nextafter(r, 1e30f));
      }
      for (std::size_t build = 0; build < detail::interpolateProfileBuilds(); ++build) {
        std::vector<float> sigma(at.size(), -1.0f), extent(at.size(), -1.0f);
        std::vector<float> sigma2(at.size(), -1.0f), extent2(at.size(), -1.0f);
        detail::interpolateProfileWithBuild(build, profile.range, profile.sigma, at.data(), sigma.data(), at.size());
        detail::interpolateProfileWithBuild(build, profile.range, profile.extent, at.data(), extent.data(), at.size());
        detail::interpolateProfileWithBuild(build, profile.range, profile.sigma, at.data(), sigma2.data(), at.size(),
                                            &profile.extent, extent2.data());
        for (std::size_t i = 0; i < at.size(); ++i) {
          const float s = profile.sigmaAt(at[i]), e = profile.extentAt(at[i]);
          EXPECT_EQ(std::memcmp(&sigma[i], &s, sizeof(float)), 0) << "build " << build << " bins " << bins << " trial "
                                                                  << trial << " rho " << at[i] << ": " << sigma[i]
                                                                  << " vs " << s;
          EXPECT_EQ(std::memcmp(&extent[i], &e, sizeof(float)), 0) << "build " << build << " bins " << bins << " trial "
                                                                   << trial << " rho " << at[i] << ": " << extent[i]
                                                                   << " vs " << e;
          EXPECT_EQ(std::memcmp(&sigma2[i], &s, sizeof(float)), 0) << "build " << build << " (two profiles)";
          EXPECT_EQ(std::memcmp(&extent2[i], &e, sizeof(float)), 0) << "build " << build << " (two profiles)";
        }
      }
    }
}

// The interpolation by several threads, in blocks of points, is the one-call interpolation to the
// bit, with and without a second profile, for sizes that do not fill the last block.
TEST(NoiseProfile, ThreadedInterpolationIsTheSerialOne)
{
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const std::vector<float> range = {0.5f, 0.9f, 1.4f, 2.0f, 2.7f, 3.5f}, sigma = {1, 3, 2, 5, 4, 6},
                           extent = {6, 5, 4, 3, 2, 1};
  for (std::size_t n : {std::size_t(1), std::size_t(4095), std::size_t(3 * 4096 + 123)}) {
    std::vector<float> at(n);
    for (float& r : at)
      r = 4.0f * u(rng);
    std::vector<float> s1(n), e1(n);
    detail::interpolateProfile(range, sigma, at.data(), s1.data(), n, &extent, e1.data());
    for (int threads : {1, 2, 3}) {
      std::vector<float> s(n, -1.0f), e(n, -1.0f), alone(n, -1.0f);
      detail::interpolateProfile(range, sigma, at.data(), s.data(), n, threads, &extent, e.data());
      detail::interpolateProfile(range, sigma, at.data(), alone.data(), n, threads);
      EXPECT_EQ(std::memcmp(s.data(), s1.data(), n * sizeof(float)), 0) << n << " points, " << threads << " threads";
      EXPECT_EQ(std::memcmp(e.data(), e1.data(), n * sizeof(float)), 0) << n << " points, " << threads << " threads";
      EXPECT_EQ(std::memcmp(alone.data(), s1.data(), n * sizeof(float)), 0) << n << " points, " << threads;
    }
  }
}

// The noise profile's sampled windows and the noise correlation's lags are evaluated by several
// threads: the same result as one thread, to the bit.
TEST(NoiseProfile, EstimatesDoNotDependOnTheThreadCount)
{
  SceneOptions o = planeScene("stereo", 160, 120);
  o.scene = SceneType::boxes;
  o.dropout = 0.05;
  const Grid frame = gridOf(renderSequence(o).front().noisy);
  const NoiseProfile one = estimateNoiseProfile(frame, 9, 1000, 3, kOrigin);
  const NoiseCorrelation c1 = estimateNoiseCorrelation(frame);
  ASSERT_FALSE(one.empty());
  for (int threads : {2, 3}) {
    const NoiseProfile many = detail::estimateNoiseProfile(frame, 9, 1000, 3, kOrigin, threads);
    EXPECT_EQ(many.range, one.range) << threads;
    EXPECT_EQ(many.sigma, one.sigma) << threads;
    EXPECT_EQ(many.extent, one.extent) << threads;
    const NoiseCorrelation cn = detail::estimateNoiseCorrelation(frame, 4, threads);
    EXPECT_EQ(cn.scale, c1.scale) << threads;
    EXPECT_EQ(cn.samples, c1.samples) << threads;
    EXPECT_EQ(detail::automaticDilation(frame, threads), automaticDilation(frame));
  }
}

namespace
{
/// A fronto-parallel plane at z = 1 m (160 x 120, f = 131.25 px), every point moved along z by
/// independent noise of `sigma` metres, and normals tilted by `tilt` radians about the y axis.
struct PlaneWithNormals
{
  Grid grid;
  NormalField normals;
};

PlaneWithNormals
noisyPlane(float sigma, float tilt, std::uint64_t seed = 3)
{
  PlaneWithNormals out;
  Grid& g = out.grid;
  g.width = 160;
  g.height = 120;
  const std::size_t n = static_cast<std::size_t>(g.width) * g.height;
  g.x.resize(n), g.y.resize(n), g.z.resize(n);
  g.valid.assign(n, 1);
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  const float f = 131.25f;
  for (int v = 0; v < g.height; ++v)
    for (int u = 0; u < g.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * g.width + u;
      g.z[i] = 1.0f + sigma * noise(rng);
      g.x[i] = (u - 0.5f * (g.width - 1)) / f;
      g.y[i] = (v - 0.5f * (g.height - 1)) / f;
    }
  out.normals.nx.assign(n, std::sin(tilt));
  out.normals.ny.assign(n, 0.0f);
  out.normals.nz.assign(n, -std::cos(tilt));
  return out;
}

std::vector<float>
spreadOf(const PlaneWithNormals& p, int threads = 1, float quantile = 0.25f)
{
  std::vector<float> range, spread;
  detail::estimatePatchSpread(p.grid, p.normals, 9, 3, 1000, 7, kOrigin, threads, quantile, range, spread);
  return spread;
}
} // namespace

// The patch spread (FilterParameters::similarity_spread) is how far apart the patches of one
// surface are: 0 on a noise-free plane with exact normals; with independent noise of sigma and
// exact normals Sim of a 3 x 3 patch pair is 2 sigma^2 times a chi-square of 9 degrees of freedom
// over 9, whose lower quartile is 0.66 (spread 1.15 sigma); normals tilted against the plane add
// the height the tilt gives the candidates' offsets, so the spread grows with the tilt; a higher
// quantile gives a larger spread.
TEST(PatchSpread, IsTheDistanceOfPatchesOfOneSurface)
{
  const std::vector<float> clean = spreadOf(noisyPlane(0.0f, 0.0f));
  ASSERT_FALSE(clean.empty());
  for (float s : clean)
    EXPECT_LT(s, 1e-6f);
  const float sigma = 0.001f;
  const std::vector<float> noisy = spreadOf(noisyPlane(sigma, 0.0f));
  ASSERT_FALSE(noisy.empty());
  for (float s : noisy) {
    EXPECT_GT(s, 1.0f * sigma);
    EXPECT_LT(s, 1.3f * sigma);
  }
  const std::vector<float> tilted = spreadOf(noisyPlane(sigma, 0.2f));
  ASSERT_EQ(tilted.size(), noisy.size());
  for (std::size_t b = 0; b < noisy.size(); ++b)
    EXPECT_GT(tilted[b], 1.5f * noisy[b]) << b;
  const std::vector<float> median = spreadOf(noisyPlane(sigma, 0.0f), 1, 0.5f);
  ASSERT_EQ(median.size(), noisy.size());
  for (std::size_t b = 0; b < noisy.size(); ++b)
    EXPECT_GT(median[b], noisy[b]) << b;
}

// The patch spread's samples are evaluated by several threads: the same result as one thread, to
// the bit; a frame without valid points gives an empty profile.
TEST(PatchSpread, DoesNotDependOnTheThreadCount)
{
  SceneOptions o = planeScene("stereo", 160, 120);
  o.scene = SceneType::boxes;
  o.dropout = 0.05;
  const Grid frame = gridOf(renderSequence(o).front().noisy);
  const NormalField normals = detail::estimateNormalsGated(frame, 7, kOrigin, 1, {}, 0);
  std::vector<float> range1, spread1;
  detail::estimatePatchSpread(frame, normals, 9, 3, 1000, 5, kOrigin, 1, 0.25f, range1, spread1);
  ASSERT_FALSE(range1.empty());
  for (int threads : {2, 3}) {
    std::vector<float> range, spread;
    detail::estimatePatchSpread(frame, normals, 9, 3, 1000, 5, kOrigin, threads, 0.25f, range, spread);
    EXPECT_EQ(range, range1) << threads;
    EXPECT_EQ(spread, spread1) << threads;
  }
  Grid empty = frame;
  std::fill(empty.valid.begin(), empty.valid.end(), 0);
  std::vector<float> range{1.0f}, spread{1.0f};
  detail::estimatePatchSpread(empty, normals, 9, 3, 1000, 5, kOrigin, 1, 0.25f, range, spread);
  EXPECT_TRUE(range.empty());
  EXPECT_TRUE(spread.empty());
}
