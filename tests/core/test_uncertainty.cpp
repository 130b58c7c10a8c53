// The per-point uncertainty (FilterParameters::uncertainty): the weights' spread and effective
// number of candidates in both evaluations and every kernel build, and the propagated standard
// deviation of the pipeline (src/core/stages/uncertainty.cpp).
#include "test_support.h"

#include "core/internal.h"
#include "core/simd/kernels.h"

#include <range_nlm/core/pipeline.h>
#include <range_nlm/eval/synthetic_scene.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
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

/// A slanted plane with a step, Gaussian noise `sigma` along the rays and some holes.
Grid
steppedSurface(int w, int h, double sigma, std::uint64_t seed, double holes = 0.1)
{
  auto cloud = test::makeCloud(
      w, h, [w](double a, double, int u, int) { return 1.0 + 0.2 * a + (u > w / 2 ? 0.05 : 0.0); }, sigma, seed);
  test::punchHoles(cloud, holes, seed + 1);
  return gridOf(cloud);
}

double
maxDifference(const std::vector<float>& a, const std::vector<float>& b)
{
  double m = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i)
    m = std::max(m, double(std::fabs(a[i] - b[i])));
  return m;
}

double
medianOf(std::vector<float> v)
{
  v.erase(std::remove_if(v.begin(), v.end(), [](float x) { return !std::isfinite(x); }), v.end());
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

FilterRun
filtered(const Grid& g, int threads = 2, bool uncertainty = true)
{
  FilterParameters p = FilterParameters::recommended();
  p.threads = threads;
  p.uncertainty = uncertainty;
  return runFilter({&g}, 0, p, kOrigin, {});
}
} // namespace

TEST(OffsetSpread, EveryKernelBuildMatchesTheDirectEvaluation)
{
  for (int holes = 0; holes < 2; ++holes) {
    const Grid grid = steppedSurface(37, 21, 0.004, 5 + holes, holes ? 0.15 : 0.0);
    const NormalField normals = estimateNormals(grid, 3, kOrigin, 1);
    std::vector<float> gate(grid.size(), 0.02f);
    for (int patch : {3, 5, 7})
      for (int gated = 0; gated < 2; ++gated) {
        const std::vector<FrameTerm> terms{{&grid, 0.02f, 0.004f, 1.0f}};
        const std::vector<float>& g = gated ? gate : std::vector<float>();
        std::vector<float> direct(grid.size());
        detail::OffsetSpread reference;
        detail::computeOffsetsDirect(grid, normals, terms, 9, patch, 2, {}, direct, g, &reference);
        double largest = 0.0;
        for (float v : reference.variance)
          largest = std::max(largest, double(v));
        ASSERT_GT(largest, 1e-6) << "the noise must give the candidates a spread";
        for (const detail::RowKernels* kernels : detail::supportedRowKernels()) {
          std::vector<float> fast(grid.size()), plain(grid.size());
          detail::OffsetSpread spread;
          detail::computeOffsetsWindowed(*kernels, grid, normals, terms, 9, patch, 2, {}, fast, g, nullptr, &spread);
          detail::computeOffsetsWindowed(*kernels, grid, normals, terms, 9, patch, 2, {}, plain, g);
          // The accumulators change nothing in the offsets.
          EXPECT_EQ(std::memcmp(fast.data(), plain.data(), fast.size() * sizeof(float)), 0);
          EXPECT_LT(maxDifference(fast, direct), 2e-6) << "patch " << patch;
          EXPECT_LT(maxDifference(spread.variance, reference.variance), 1e-4 * largest) << "patch " << patch;
          EXPECT_LT(maxDifference(spread.inverse_count, reference.inverse_count), 1e-5) << "patch " << patch;
        }
      }
  }
}

TEST(OffsetSpread, SeveralFramesWeighTheirSumsByPsi)
{
  const Grid a = steppedSurface(31, 19, 0.004, 1), b = steppedSurface(31, 19, 0.004, 2);
  const NormalField normals = estimateNormals(b, 3, kOrigin, 1);
  const std::vector<FrameTerm> terms{{&a, 0.03f, 0.005f, 0.3f}, {&b, 0.02f, 0.004f, 1.0f}};
  std::vector<float> fast, direct;
  detail::OffsetSpread s_fast, s_direct;
  detail::computeOffsets(b, normals, terms, 7, 3, Evaluation::fast, 2, {}, fast, {}, nullptr, &s_fast);
  detail::computeOffsets(b, normals, terms, 7, 3, Evaluation::direct, 2, {}, direct, {}, nullptr, &s_direct);
  EXPECT_LT(maxDifference(s_fast.variance, s_direct.variance), 1e-9);
  EXPECT_LT(maxDifference(s_fast.inverse_count, s_direct.inverse_count), 1e-5);
}

TEST(OffsetSpread, OneCandidateHasNoSpreadAndCountsOne)
{
  // A 1 x 1 search window: the point itself is the only candidate.
  const Grid grid = steppedSurface(16, 16, 0.004, 3, 0.0);
  const NormalField normals = estimateNormals(grid, 3, kOrigin, 1);
  std::vector<float> offsets;
  detail::OffsetSpread spread;
  detail::computeOffsets(grid, normals, {{&grid, 0.02f, 0.004f, 1.0f}}, 1, 3, Evaluation::fast, 1, {}, offsets, {},
                         nullptr, &spread);
  for (std::size_t i = 0; i < grid.size(); ++i)
    if (std::isfinite(normals.nx[i])) {
      EXPECT_EQ(spread.variance[i], 0.0f);
      EXPECT_EQ(spread.inverse_count[i], 1.0f);
    }
}

TEST(Uncertainty, OffByDefaultAndTheOutputDoesNotDependOnIt)
{
  EXPECT_FALSE(FilterParameters::recommended().uncertainty);
  const Grid g = steppedSurface(64, 48, 0.003, 9);
  const FilterRun off = filtered(g, 2, false), on = filtered(g, 2, true);
  EXPECT_TRUE(off.uncertainty.empty());
  ASSERT_EQ(on.uncertainty.size(), g.size());
  EXPECT_EQ(std::memcmp(off.output.z.data(), on.output.z.data(), g.size() * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(off.output.x.data(), on.output.x.data(), g.size() * sizeof(float)), 0);
  for (std::size_t i = 0; i < g.size(); ++i)
    EXPECT_EQ(std::isfinite(on.uncertainty[i]), bool(on.output.valid[i])) << i;
}

TEST(Uncertainty, ZeroNoiseGivesNearlyZero)
{
  auto cloud = test::makeCloud(64, 48, test::plane(Eigen::Vector3d(0.1, 0.05, 1.0), 1.2), 0.0, 1);
  const FilterRun run = filtered(gridOf(cloud));
  for (float s : run.uncertainty)
    if (std::isfinite(s))
      EXPECT_LT(s, 1e-6f);
}

TEST(Uncertainty, DoublingTheNoiseDoublesIt)
{
  const auto surface = test::plane(Eigen::Vector3d(0.1, 0.05, 1.0), 1.2);
  const FilterRun once = filtered(gridOf(test::makeCloud(80, 60, surface, 0.002, 4)));
  const FilterRun twice = filtered(gridOf(test::makeCloud(80, 60, surface, 0.004, 4)));
  const double ratio = medianOf(twice.uncertainty) / medianOf(once.uncertainty);
  EXPECT_GT(ratio, 1.7);
  EXPECT_LT(ratio, 2.3);
  // And it is below the noise: the filter averaged.
  EXPECT_LT(medianOf(once.uncertainty), 0.002);
  EXPECT_GT(medianOf(once.uncertainty), 0.0002);
}

TEST(Uncertainty, TheSameForOneTwoAndThreeThreads)
{
  SceneOptions o;
  o.width = 96;
  o.height = 72;
  o.fx = o.fy = 525.0 * 96 / 640;
  o.noise = NoiseModel::stereo; // dilated passes
  const Grid g = gridOf(renderFrame(o).noisy);
  const FilterRun one = filtered(g, 1), two = filtered(g, 2), three = filtered(g, 3);
  ASSERT_EQ(one.uncertainty.size(), g.size());
  EXPECT_EQ(std::memcmp(one.uncertainty.data(), two.uncertainty.data(), g.size() * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(one.uncertainty.data(), three.uncertainty.data(), g.size() * sizeof(float)), 0);
}

TEST(Uncertainty, TheDirectEvaluationGivesTheSame)
{
  const Grid g = steppedSurface(48, 40, 0.003, 12);
  FilterParameters p = FilterParameters::recommended();
  p.uncertainty = true;
  p.threads = 2;
  const FilterRun fast = runFilter({&g}, 0, p, kOrigin, {});
  p.evaluation = Evaluation::direct;
  const FilterRun direct = runFilter({&g}, 0, p, kOrigin, {});
  double largest = 0.0;
  for (float s : direct.uncertainty)
    if (std::isfinite(s))
      largest = std::max(largest, double(s));
  for (std::size_t i = 0; i < g.size(); ++i)
    if (std::isfinite(direct.uncertainty[i]))
      EXPECT_NEAR(fast.uncertainty[i], direct.uncertainty[i], 1e-3 * largest) << i;
}
