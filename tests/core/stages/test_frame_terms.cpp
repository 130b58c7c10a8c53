// The frame terms (src/core/stages/frame_terms.cpp): the similarity bandwidth from the frame's
// patch spread (FilterParameters::similarity_spread).
#include "../frame_fixtures.h"

#include <range_nlm/eval/metrics.h>
#include <range_nlm/parameters.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace range_nlm;
using namespace range_nlm::test;

namespace
{
/// The ridges scene (small features, docs/quality.md) at 320 x 240 with laser-grade noise.
SyntheticFrame
ridgesFrame()
{
  SceneOptions o = planeScene("laser", 320, 240);
  o.scene = SceneType::ridges;
  o.seed = 7;
  return renderFrame(o, 0);
}

Grid
filtered(const Grid& frame, const FilterParameters& p)
{
  return runFilter({&frame}, 0, p, kOrigin, {}).output;
}

pcl::PointCloud<pcl::PointXYZ>
cloudOf(const Grid& g)
{
  pcl::PointCloud<pcl::PointXYZ> c;
  c.width = static_cast<std::uint32_t>(g.width);
  c.height = static_cast<std::uint32_t>(g.height);
  c.is_dense = false;
  c.points.resize(g.size());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < g.size(); ++i)
    c.points[i] = g.valid[i] ? pcl::PointXYZ(g.x[i], g.y[i], g.z[i]) : pcl::PointXYZ(nan, nan, nan);
  return c;
}

/// The default's similarity_spread (docs/quality.md, "Small features at low noise").
constexpr float kSpread = 3.0f;
} // namespace

// Off (0) is the default's s = similarity_scale * sigma; s is never wider than that, so a spread
// factor so large that the cap holds everywhere gives the same bits as off.
TEST(SimilaritySpread, IsCappedAtTheDefaultBandwidth)
{
  const SyntheticFrame scene = ridgesFrame();
  const Grid frame = gridOf(scene.noisy);
  FilterParameters p;
  p.threads = 2;
  p.similarity_spread = 0.0f;
  const Grid off = filtered(frame, p);
  p.similarity_spread = 1000.0f;
  EXPECT_TRUE(sameBits(filtered(frame, p), off));
}

// At laser-grade noise the patches of one surface are closer than 3 sigma: s from the spread is
// narrower, and the small features come out sharper (lower feature RMSE against the truth)
// without losing the flat regions' accuracy by more than a few per cent; the same bits on 1, 2
// and 3 threads.
TEST(SimilaritySpread, KeepsSmallFeaturesAtLowNoise)
{
  const SyntheticFrame scene = ridgesFrame();
  const Grid frame = gridOf(scene.noisy);
  FilterParameters p;
  p.threads = 1;
  p.similarity_spread = 0.0f;
  const FrameMetrics off = evaluateFrame(scene.truth, cloudOf(filtered(frame, p)), &scene.noisy);
  p.similarity_spread = kSpread;
  const Grid one = filtered(frame, p);
  const FrameMetrics on = evaluateFrame(scene.truth, cloudOf(one), &scene.noisy);
  EXPECT_LT(on.feature_rmse, 0.95 * off.feature_rmse) << on.feature_rmse << " vs " << off.feature_rmse;
  EXPECT_LT(on.flat_rmse, 1.05 * off.flat_rmse) << on.flat_rmse << " vs " << off.flat_rmse;
  for (int threads : {2, 3}) {
    p.threads = threads;
    EXPECT_TRUE(sameBits(filtered(frame, p), one)) << threads;
  }
}
