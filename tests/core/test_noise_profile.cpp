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
// estimateNoiseProfile leaves them), and for any count of points (blocks and their tails).
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
      std::vector<float> sigma(at.size(), -1.0f), extent(at.size(), -1.0f);
      detail::interpolateProfile(profile.range, profile.sigma, at.data(), sigma.data(), at.size());
      detail::interpolateProfile(profile.range, profile.extent, at.data(), extent.data(), at.size());
      for (std::size_t i = 0; i < at.size(); ++i) {
        const float s = profile.sigmaAt(at[i]), e = profile.extentAt(at[i]);
        EXPECT_EQ(std::memcmp(&sigma[i], &s, sizeof(float)), 0)
            << "bins " << bins << " trial " << trial << " rho " << at[i] << ": " << sigma[i] << " vs " << s;
        EXPECT_EQ(std::memcmp(&extent[i], &e, sizeof(float)), 0)
            << "bins " << bins << " trial " << trial << " rho " << at[i] << ": " << extent[i] << " vs " << e;
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
