// The fast (windowed) kernel against the direct one, and the small math helpers.
#include "test_support.h"

#include "core/internal.h"
#include "core/simd/kernels.h"

#include <range_nlm/core/pipeline.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

using namespace range_nlm;

namespace
{
Grid
randomSurface(int w, int h, double hole_probability, std::uint64_t seed)
{
  auto cloud = test::makeCloud(w, h, [](double a, double b, int u, int) { return 1.0 + 0.2 * a + (u > 10 ? 0.15 : 0.0) + 0.1 * b * b; },
                               0.004, seed);
  test::punchHoles(cloud, hole_probability, seed + 1);
  return Grid::fromInterleaved(&cloud[0].x, w, h, sizeof(pcl::PointXYZ) / sizeof(float));
}

double
maxDifference(const std::vector<float>& a, const std::vector<float>& b)
{
  double m = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i)
    m = std::max(m, double(std::fabs(a[i] - b[i])));
  return m;
}
} // namespace

TEST(Kernel, ExpMatchesStdExp)
{
  for (float x = -90.0f; x <= 0.0f; x += 0.01f) {
    const float expected = std::exp(x);
    const float got = detail::expNonPositive(x);
    if (x < -87.0f)
      EXPECT_EQ(got, 0.0f);
    else
      EXPECT_NEAR(got, expected, 4e-7f * expected + 1e-38f) << x;
  }
  EXPECT_EQ(detail::expNonPositive(-std::numeric_limits<float>::infinity()), 0.0f);
}

TEST(Kernel, FastMatchesDirectOnHolesBordersAndWindowSizes)
{
  const Viewpoint origin{0, 0, 0};
  for (int holes = 0; holes < 2; ++holes) {
    const Grid grid = randomSurface(23, 17, holes ? 0.15 : 0.0, 7 + holes);
    const NormalField normals = estimateNormals(grid, 3, origin, 1);
    for (int search : {1, 3, 5, 7, 9})
      for (int patch : {1, 3, 5, 7, 11}) {
        const std::vector<FrameTerm> terms{{&grid, 0.02f, 0.004f, 1.0f}};
        std::vector<float> fast, direct;
        computeOffsets(grid, normals, terms, search, patch, Evaluation::fast, 2, {}, fast);
        computeOffsets(grid, normals, terms, search, patch, Evaluation::direct, 2, {}, direct);
        EXPECT_LT(maxDifference(fast, direct), 2e-6) << "search " << search << " patch " << patch;
      }
  }
}

TEST(Kernel, FastMatchesDirectWithSeveralFrames)
{
  const Viewpoint origin{0, 0, 0};
  const Grid a = randomSurface(31, 19, 0.1, 1), b = randomSurface(31, 19, 0.1, 2), c = randomSurface(31, 19, 0.1, 3);
  const NormalField normals = estimateNormals(b, 3, origin, 1);
  const std::vector<FrameTerm> terms{{&a, 0.03f, 0.005f, 0.3f}, {&b, 0.02f, 0.004f, 1.0f}, {&c, 0.025f, 0.006f, 0.2f}};
  std::vector<float> fast, direct;
  computeOffsets(b, normals, terms, 7, 5, Evaluation::fast, 2, {}, fast);
  computeOffsets(b, normals, terms, 7, 5, Evaluation::direct, 2, {}, direct);
  EXPECT_LT(maxDifference(fast, direct), 2e-6);
}

TEST(Kernel, FastMatchesDirectOnAWideFrameWithPerPointBandwidths)
{
  // A wide frame whose width is no multiple of the vector width, with holes, per-point bandwidth
  // maps and three frames: rows of vectors with and without holes, their last partial vector,
  // and the per-pixel maps must give the literal formula.
  const Viewpoint origin{0, 0, 0};
  const int w = 300, h = 75;
  const Grid a = randomSurface(w, h, 0.1, 11), b = randomSurface(w, h, 0.1, 12), c = randomSurface(w, h, 0.1, 13);
  const NormalField normals = estimateNormals(b, 3, origin, 1);
  std::vector<float> inv_d2(b.size()), inv_s2(b.size());
  for (std::size_t i = 0; i < b.size(); ++i) {
    inv_d2[i] = 1.0f / std::pow(0.015f + 0.00002f * float(i % 997), 2.0f);
    inv_s2[i] = 1.0f / std::pow(0.003f + 0.000003f * float(i % 661), 2.0f);
  }
  FrameTerm centre{&b, 0.0f, 0.0f, 1.0f};
  centre.inverse_distance2 = &inv_d2;
  centre.inverse_similarity2 = &inv_s2;
  const std::vector<FrameTerm> terms{{&a, 0.03f, 0.005f, 0.3f}, centre, {&c, 0.025f, 0.006f, 0.2f}};
  std::vector<float> fast, direct;
  computeOffsets(b, normals, terms, 9, 5, Evaluation::fast, 2, {}, fast);
  computeOffsets(b, normals, terms, 9, 5, Evaluation::direct, 2, {}, direct);
  EXPECT_LT(maxDifference(fast, direct), 2e-6);
  std::size_t moved = 0;
  for (float o : fast)
    moved += o != 0.0f;
  EXPECT_GT(moved, b.size() / 2);
  computeOffsets(b, normals, {centre}, 5, 11, Evaluation::fast, 3, {}, fast);
  computeOffsets(b, normals, {centre}, 5, 11, Evaluation::direct, 3, {}, direct);
  EXPECT_LT(maxDifference(fast, direct), 2e-6);
}

// A frame searched over a smaller window (FrameTerm::search_window, a stream's history) gives the
// literal rule in every build: its sums scaled by the centre frame's weight over the whole window
// relative to the inner one, with holes, per-point bandwidths, the patch gate and the spread. The
// centre frame's rows through the inner window are summed as whole rows where a row is one block
// (search 7 and 9, patches up to 5), their weights split between the two windows.
TEST(Kernel, FramesWithASmallerSearchWindowMatchDirectInEveryBuild)
{
  const Viewpoint origin{0, 0, 0};
  const std::vector<const detail::RowKernels*> builds = detail::supportedRowKernels();
  for (int holes = 0; holes < 2; ++holes) {
    const int w = 37, h = 23;
    const Grid a = randomSurface(w, h, holes ? 0.12 : 0.0, 60), b = randomSurface(w, h, holes ? 0.12 : 0.0, 61);
    const NormalField normals = estimateNormals(b, 3, origin, 1);
    std::vector<float> inv_d2(b.size()), gate(b.size());
    for (std::size_t i = 0; i < b.size(); ++i) {
      inv_d2[i] = 1.0f / std::pow(0.015f + 0.00003f * float(i % 97), 2.0f);
      gate[i] = 0.01f + 0.0001f * float(i % 13);
    }
    FrameTerm centre{&b, 0.0f, 0.004f, 1.0f};
    centre.inverse_distance2 = &inv_d2;
    for (int search : {5, 7, 9}) // (7 and 9: the centre frame's rows summed whole, their weights split)
      for (int inner : {1, 3, 5})
        for (int patch : {1, 3, 5, 13}) {
          if (inner > search)
            continue;
          FrameTerm history{&a, 0.03f, 0.005f, 0.6f};
          history.search_window = inner;
          const std::vector<FrameTerm> terms{history, centre};
          std::vector<float> direct, fast;
          detail::OffsetSpread direct_spread, fast_spread;
          detail::computeOffsets(b, normals, terms, search, patch, Evaluation::direct, 2, {}, direct, gate, nullptr,
                                 &direct_spread);
          for (std::size_t k = 0; k < builds.size(); ++k) {
            fast.assign(b.size(), -1.0f);
            detail::computeOffsetsWindowed(*builds[k], b, normals, terms, search, patch, 2, {}, fast, gate, nullptr,
                                           &fast_spread);
            const std::string what = "build " + std::to_string(k) + " holes " + std::to_string(holes) + " search " +
                                     std::to_string(search) + " inner " + std::to_string(inner) + " patch " +
                                     std::to_string(patch);
            EXPECT_LT(maxDifference(fast, direct), 2e-6) << what;
            EXPECT_LT(maxDifference(fast_spread.inverse_count, direct_spread.inverse_count), 2e-5) << what;
          }
        }
  }
}

// The scale is the centre frame's weight over its whole window relative to the inner one: a copy
// of the frame searched over its co-located pixel only (inner window 1, height 0, weight 1, scaled
// to the centre frame's whole weight) halves every offset, as if it held the weight of the whole
// window at height 0. Naming the search window itself changes nothing.
TEST(Kernel, AFrameSearchedOverASmallerWindowStandsForItsWholeWindow)
{
  const Viewpoint origin{0, 0, 0};
  const Grid b = randomSurface(29, 21, 0.0, 70);
  const NormalField normals = estimateNormals(b, 3, origin, 1);
  const FrameTerm centre{&b, 0.02f, 0.004f, 1.0f};
  std::vector<float> single, with_copy;
  computeOffsets(b, normals, {centre}, 7, 3, Evaluation::fast, 2, {}, single);
  FrameTerm copy = centre;
  copy.search_window = 1;
  computeOffsets(b, normals, {copy, centre}, 7, 3, Evaluation::fast, 2, {}, with_copy);
  std::size_t moved = 0;
  for (std::size_t i = 0; i < b.size(); ++i) {
    EXPECT_NEAR(with_copy[i], 0.5f * single[i], 1e-6f + 1e-5f * std::fabs(single[i])) << i;
    moved += std::fabs(single[i]) > 1e-4f;
  }
  EXPECT_GT(moved, b.size() / 4);
  const Grid a = randomSurface(29, 21, 0.1, 71);
  FrameTerm other{&a, 0.03f, 0.005f, 0.5f};
  std::vector<float> whole, named;
  computeOffsets(b, normals, {other, centre}, 7, 3, Evaluation::fast, 2, {}, whole);
  other.search_window = 7;
  computeOffsets(b, normals, {other, centre}, 7, 3, Evaluation::fast, 2, {}, named);
  EXPECT_EQ(maxDifference(whole, named), 0.0);
}

TEST(Kernel, FrameSearchWindowsAreChecked)
{
  const Viewpoint origin{0, 0, 0};
  const Grid a = randomSurface(15, 11, 0.0, 80), b = randomSurface(15, 11, 0.0, 81), c = randomSurface(15, 11, 0.0, 82);
  const NormalField normals = estimateNormals(b, 3, origin, 1);
  std::vector<float> out;
  for (int bad : {-1, 4, 9}) {
    FrameTerm other{&a, 0.03f, 0.005f, 0.5f};
    other.search_window = bad;
    try {
      computeOffsets(b, normals, {other, FrameTerm{&b, 0.02f, 0.004f, 1.0f}}, 7, 3, Evaluation::fast, 1, {}, out);
      ADD_FAILURE() << "search window " << bad << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("search window " + std::to_string(bad)), std::string::npos) << e.what();
    }
  }
  // Two different smaller windows: the rule scales one.
  FrameTerm three{&a, 0.03f, 0.005f, 0.5f}, five{&c, 0.03f, 0.005f, 0.5f};
  three.search_window = 3;
  five.search_window = 5;
  EXPECT_THROW(computeOffsets(b, normals, {three, FrameTerm{&b, 0.02f, 0.004f, 1.0f}, five}, 7, 3, Evaluation::fast,
                              1, {}, out),
               std::invalid_argument);
}

TEST(Kernel, EveryInstructionSetBuildMatchesDirect)
{
  // The baseline, AVX2 and AVX-512 builds this CPU runs (computeOffsets takes only the fastest),
  // on widths around the vector widths, with and without holes, three frames, the compile-time
  // patch sizes and a run-time one (13), remainders of the blocks of four shifts (search 1 .. 9),
  // and the correlation sums (patches of 7 and more without holes).
  const Viewpoint origin{0, 0, 0};
  const std::vector<const detail::RowKernels*> builds = detail::supportedRowKernels();
  ASSERT_GE(builds.size(), 1u);
  for (int holes = 0; holes < 2; ++holes)
    for (int w : {7, 17, 33}) {
      const Grid a = randomSurface(w, 21, holes ? 0.12 : 0.0, 40 + w);
      const Grid b = randomSurface(w, 21, holes ? 0.12 : 0.0, 41 + w);
      const NormalField normals = estimateNormals(b, 3, origin, 1);
      const std::vector<FrameTerm> terms{{&a, 0.03f, 0.005f, 0.4f}, {&b, 0.02f, 0.004f, 1.0f}};
      for (int search : {1, 3, 5, 7, 9})
        for (int patch : {1, 3, 5, 7, 9, 11, 13}) {
          std::vector<float> direct;
          computeOffsets(b, normals, terms, search, patch, Evaluation::direct, 2, {}, direct);
          for (std::size_t k = 0; k < builds.size(); ++k) {
            std::vector<float> fast(b.size(), -1.0f);
            detail::computeOffsetsWindowed(*builds[k], b, normals, terms, search, patch, 2, {}, fast);
            EXPECT_LT(maxDifference(fast, direct), 2e-6)
                << "build " << k << " width " << w << " holes " << holes << " search " << search << " patch " << patch;
          }
        }
    }
}

// The range pre-smoothing's window sums (RowKernels::window_smoothing) of every instruction-set
// build against the scalar rule, one offset at a time in raster order, on widths around the
// block of 16 centres (the last width % 16 take the scalar tail), with holes (flag 0) and
// per-centre bandwidths, including 0 (inv = 0: every valid neighbour weighs 1).
TEST(Kernel, PresmoothingWindowSumsOfEveryBuildAreTheScalarRule)
{
  const std::vector<const detail::RowKernels*> builds = detail::supportedRowKernels();
  ASSERT_GE(builds.size(), 1u);
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> range(0.8f, 3.0f), noise(-0.01f, 0.01f), unit(0.0f, 1.0f);
  for (int r : {1, 3})
    for (int width : {5, 16, 37}) {
      const int rows = 2 * r + 1;
      const std::ptrdiff_t stride = width + 2 * r;
      std::vector<float> rho(static_cast<std::size_t>(stride) * rows), flag(rho.size()), inv(width);
      for (std::size_t i = 0; i < rho.size(); ++i) {
        flag[i] = unit(rng) < 0.15f ? 0.0f : 1.0f;
        rho[i] = flag[i] > 0.0f ? 1.5f + noise(rng) : 0.0f;
      }
      for (int u = 0; u < width; ++u) {
        const float sigma = u % 7 == 0 ? 0.0f : 0.002f + 0.01f * unit(rng);
        inv[u] = sigma > 0.0f ? 1.0f / (2.0f * sigma * sigma) : 0.0f;
      }
      const float* centre = &rho[static_cast<std::size_t>(r) * stride + r];
      const float* centre_flag = &flag[static_cast<std::size_t>(r) * stride + r];
      for (std::size_t k = 0; k < builds.size(); ++k) {
        std::vector<float> num(width, -1.0f), den(width, -1.0f);
        builds[k]->window_smoothing(centre, centre_flag, stride, r, inv.data(), width, num.data(), den.data());
        for (int u = 0; u < width; ++u) {
          double nu = 0.0, de = 0.0;
          for (int dv = -r; dv <= r; ++dv)
            for (int du = -r; du <= r; ++du) {
              const std::ptrdiff_t o = dv * stride + du + u;
              const double d = double(centre[o]) - centre[u];
              const double w = centre_flag[o] * std::exp(-d * d * inv[u]);
              nu += w * d;
              de += w;
            }
          EXPECT_NEAR(den[u], de, 1e-5 * (1.0 + de)) << "build " << k << " r " << r << " width " << width << " u " << u;
          EXPECT_NEAR(num[u], nu, 1e-7 + 1e-5 * std::fabs(nu)) << "build " << k << " r " << r << " width " << width;
        }
      }
    }
}

// A patch guide (FrameTerm::patches): the other frames' patches are compared with the guide's
// patch around i instead of the centre frame's, in every instruction-set build as in the direct
// evaluation, with holes where the guide and the frames differ, with guided and unguided terms
// interleaved (the kernel projects the centre patch again when its source changes); the centre
// frame named as its own guide changes nothing; a guide of another size is rejected.
TEST(Kernel, PatchGuideIsHonouredByEveryBuildAsByTheDirectEvaluation)
{
  const Viewpoint origin{0, 0, 0};
  const std::vector<const detail::RowKernels*> builds = detail::supportedRowKernels();
  ASSERT_GE(builds.size(), 1u);
  for (int holes = 0; holes < 2; ++holes) {
    const double p = holes ? 0.1 : 0.0;
    const Grid a = randomSurface(37, 23, p, 60), b = randomSurface(37, 23, p, 61), c = randomSurface(37, 23, p, 62);
    const Grid guide = randomSurface(37, 23, p, 63);
    const NormalField normals = estimateNormals(b, 3, origin, 1);
    FrameTerm ta{&a, 0.03f, 0.005f, 0.4f}, tc{&c, 0.025f, 0.006f, 0.2f};
    const FrameTerm tb{&b, 0.02f, 0.004f, 1.0f};
    const std::vector<FrameTerm> plain{ta, tb, tc};
    ta.patches = tc.patches = &guide;
    const std::vector<FrameTerm> guided{ta, tb, tc};
    for (int patch : {3, 5, 7, 9}) {
      std::vector<float> direct, unguided;
      computeOffsets(b, normals, guided, 7, patch, Evaluation::direct, 2, {}, direct);
      computeOffsets(b, normals, plain, 7, patch, Evaluation::direct, 2, {}, unguided);
      EXPECT_GT(maxDifference(direct, unguided), 1e-4) << "the guide must change the similarities";
      for (std::size_t k = 0; k < builds.size(); ++k) {
        std::vector<float> fast(b.size(), -1.0f);
        detail::computeOffsetsWindowed(*builds[k], b, normals, guided, 7, patch, 2, {}, fast);
        EXPECT_LT(maxDifference(fast, direct), 2e-6) << "build " << k << " holes " << holes << " patch " << patch;
      }
    }
    std::vector<FrameTerm> self = plain;
    for (FrameTerm& t : self)
      t.patches = &b;
    std::vector<float> with_self, without;
    computeOffsets(b, normals, self, 7, 5, Evaluation::fast, 2, {}, with_self);
    computeOffsets(b, normals, plain, 7, 5, Evaluation::fast, 2, {}, without);
    EXPECT_EQ(with_self, without);
  }
  const Grid b = randomSurface(20, 10, 0.0, 70), small = randomSurface(19, 10, 0.0, 71);
  const NormalField normals = estimateNormals(b, 3, origin, 1);
  FrameTerm t{&b, 0.02f, 0.004f, 1.0f};
  t.patches = &small;
  std::vector<float> out;
  EXPECT_THROW(computeOffsets(b, normals, {t}, 5, 3, Evaluation::fast, 1, {}, out), std::invalid_argument);
}

// The patch gate (FilterParameters::patch_edge_gate): centre patch pixels farther from i's tangent
// plane than the gate count as holes, in every instruction-set build as in the direct evaluation:
// with and without holes, three frames (one with a patch guide, whose patch is gated instead),
// per-point gates that reach the step of randomSurface but not its noise, a gate of 10 nm (every
// pixel off the plane left out) and gates that leave nothing out (the ungated result, to the bit).
// Not a gate of 0: where a normal is fitted through three points (a corner with a hole), they lie
// on the plane to rounding (< 1e-9 m here), and a gate of 0 would keep or drop them by the last
// bit of the normal, which FMA contraction changes between builds and optimisation levels; the
// nearest pixel truly off a plane here is 2.5e-7 m from it.
TEST(Kernel, PatchGateIsHonouredByEveryBuildAsByTheDirectEvaluation)
{
  const Viewpoint origin{0, 0, 0};
  const std::vector<const detail::RowKernels*> builds = detail::supportedRowKernels();
  ASSERT_GE(builds.size(), 1u);
  for (int holes = 0; holes < 2; ++holes) {
    const double p = holes ? 0.1 : 0.0;
    const Grid a = randomSurface(37, 23, p, 80), b = randomSurface(37, 23, p, 81), c = randomSurface(37, 23, p, 82);
    const Grid guide = randomSurface(37, 23, p, 83);
    const NormalField normals = estimateNormals(b, 3, origin, 1);
    FrameTerm ta{&a, 0.03f, 0.005f, 0.4f};
    ta.patches = &guide;
    const std::vector<FrameTerm> terms{ta, {&b, 0.02f, 0.004f, 1.0f}, {&c, 0.025f, 0.006f, 0.2f}};
    std::vector<float> gate(b.size()), wide(b.size(), 1e3f);
    for (std::size_t i = 0; i < gate.size(); ++i)
      gate[i] = i % 11 == 0 ? 1e-8f : 0.012f + 0.00003f * float(i % 401);
    for (int patch : {3, 5, 7, 11}) {
      std::vector<float> direct, ungated, fast_ungated(b.size(), -1.0f);
      computeOffsets(b, normals, terms, 7, patch, Evaluation::direct, 2, {}, direct, gate);
      computeOffsets(b, normals, terms, 7, patch, Evaluation::direct, 2, {}, ungated);
      EXPECT_GT(maxDifference(direct, ungated), 1e-3) << "the gate must change the similarities next to the step";
      for (std::size_t k = 0; k < builds.size(); ++k) {
        std::vector<float> fast(b.size(), -1.0f);
        detail::computeOffsetsWindowed(*builds[k], b, normals, terms, 7, patch, 2, {}, fast, gate);
        EXPECT_LT(maxDifference(fast, direct), 2e-6) << "build " << k << " holes " << holes << " patch " << patch;
        detail::computeOffsetsWindowed(*builds[k], b, normals, terms, 7, patch, 2, {}, fast, wide);
        detail::computeOffsetsWindowed(*builds[k], b, normals, terms, 7, patch, 2, {}, fast_ungated);
        EXPECT_EQ(fast, fast_ungated) << "build " << k << " holes " << holes << " patch " << patch;
      }
    }
  }
  const Grid b = randomSurface(20, 10, 0.0, 90);
  const NormalField normals = estimateNormals(b, 3, origin, 1);
  std::vector<float> out;
  EXPECT_THROW(computeOffsets(b, normals, {{&b, 0.02f, 0.004f, 1.0f}}, 5, 3, Evaluation::fast, 1, {}, out,
                              std::vector<float>(b.size() - 1, 1.0f)),
               std::invalid_argument);
}

// What the gate is for: next to a depth step the patch of a point on the far surface holds pixels
// of the near one, which only candidates at the same place along the step share (none where the
// step is ragged), so without the gate such a point keeps most of its noise; with it, it is
// compared by its own surface's pixels and averaged like the points away from the step. The
// points away from the step do not change.
TEST(Kernel, PatchGateFiltersThePointsBesideADepthStep)
{
  const Viewpoint origin{0, 0, 0};
  const int w = 48, h = 40;
  const double noise = 0.003;
  const auto edge = [](int v) { return 22 + (v * 37) % 5; }; // a ragged step between columns 22 and 26
  auto cloud = test::makeCloud(w, h, [&](double, double, int u, int v) { return u < edge(v) ? 1.0 : 1.4; }, noise, 21);
  const Grid grid = Grid::fromInterleaved(&cloud[0].x, w, h, sizeof(pcl::PointXYZ) / sizeof(float));
  // The normals of the two planes (facing the camera), as the gated fits give them.
  NormalField normals = estimateNormals(grid, 3, origin, 1);
  std::fill(normals.nx.begin(), normals.nx.end(), 0.0f);
  std::fill(normals.ny.begin(), normals.ny.end(), 0.0f);
  std::fill(normals.nz.begin(), normals.nz.end(), -1.0f);
  const std::vector<FrameTerm> terms{{&grid, 0.05f, 3.0f * float(noise), 1.0f}};
  const std::vector<float> gate(grid.size(), 18.0f * float(noise));
  std::vector<float> gated, plain;
  computeOffsets(grid, normals, terms, 9, 3, Evaluation::fast, 2, {}, gated, gate);
  computeOffsets(grid, normals, terms, 9, 3, Evaluation::fast, 2, {}, plain);
  // RMS of the filtered depth about its surface over the pixels `shift` columns right of the
  // step in each row (0: the first far one, -1: the last near one), rows away from the border.
  const auto rms = [&](const std::vector<float>& offsets, int shift) {
    double sum = 0.0;
    int count = 0;
    for (int v = 6; v < h - 6; ++v) {
      const int u = edge(v) + shift;
      const std::size_t i = std::size_t(v) * w + u;
      const double z = grid.z[i] + offsets[i]; // p' = p - h n, n = (0, 0, -1)
      const double truth = u >= edge(v) ? 1.4 : 1.0;
      sum += (z - truth) * (z - truth);
      ++count;
    }
    return std::sqrt(sum / count);
  };
  for (int shift : {-1, 0}) {
    EXPECT_GT(rms(plain, shift), 0.5 * noise)
        << "shift " << shift << ": without the gate the step's neighbours stay noisy";
    EXPECT_LT(rms(gated, shift), 0.45 * rms(plain, shift)) << "shift " << shift;
  }
  for (int shift : {-16, -12, 12, 16})
    EXPECT_NEAR(rms(gated, shift), rms(plain, shift), 0.02 * noise) << "shift " << shift;
}

TEST(Kernel, FastKeepsPrecisionWherePatchesStraddleADepthEdge)
{
  // A 0.5 m step with 0.2 mm noise: patches that straddle the step at the same place have a
  // small Sim but sums of squared heights ten thousand times larger, where A - 2C + B cancels in
  // float. The fast path must still match the literal formula (it sums those pairs again).
  const Viewpoint origin{0, 0, 0};
  auto cloud = test::makeCloud(40, 24, [](double a, double, int u, int) { return 1.0 + 0.05 * a + (u >= 20 ? 0.5 : 0.0); },
                               0.0002, 5);
  const Grid grid = Grid::fromInterleaved(&cloud[0].x, 40, 24, sizeof(pcl::PointXYZ) / sizeof(float));
  const NormalField normals = estimateNormals(grid, 3, origin, 1);
  const std::vector<FrameTerm> terms{{&grid, 0.05f, 0.0004f, 1.0f}};
  for (int patch : {7, 9, 11}) {
    std::vector<float> fast, direct;
    computeOffsets(grid, normals, terms, 7, patch, Evaluation::fast, 2, {}, fast);
    computeOffsets(grid, normals, terms, 7, patch, Evaluation::direct, 2, {}, direct);
    EXPECT_LT(maxDifference(fast, direct), 2e-7) << "patch " << patch;
  }
}

TEST(Kernel, ActiveMaskLimitsComputation)
{
  const Viewpoint origin{0, 0, 0};
  const Grid grid = randomSurface(20, 20, 0.0, 3);
  const NormalField normals = estimateNormals(grid, 3, origin, 1);
  std::vector<unsigned char> active(grid.size(), 0);
  active[5 * 20 + 5] = 1;
  std::vector<float> offsets;
  computeOffsets(grid, normals, {{&grid, 0.02f, 0.004f, 1.0f}}, 5, 3, Evaluation::fast, 1, active, offsets);
  for (std::size_t i = 0; i < offsets.size(); ++i)
    if (i != 5 * 20 + 5)
      EXPECT_EQ(offsets[i], 0.0f);
  EXPECT_NE(offsets[5 * 20 + 5], 0.0f);
}

TEST(Kernel, NormalsFaceTheViewpointAndFitPlanes)
{
  const Eigen::Vector3d n(0.3, -0.2, 1.0);
  auto cloud = test::makeCloud(15, 12, test::plane(n, 1.2), 0.0, 1);
  const Grid grid = Grid::fromInterleaved(&cloud[0].x, 15, 12, 4);
  const NormalField normals = estimateNormals(grid, 3, Viewpoint{0, 0, 0}, 1);
  const Eigen::Vector3d unit = -n.normalized(); // toward the camera at the origin
  for (std::size_t i = 0; i < grid.size(); ++i) {
    EXPECT_NEAR(normals.nx[i], unit.x(), 1e-4);
    EXPECT_NEAR(normals.ny[i], unit.y(), 1e-4);
    EXPECT_NEAR(normals.nz[i], unit.z(), 1e-4);
  }
}

TEST(Kernel, TemporalWeights)
{
  EXPECT_FLOAT_EQ(temporalDistanceWeight(3, 3), 1.0f);
  EXPECT_FLOAT_EQ(temporalDistanceWeight(2, 3), 0.5f);
  EXPECT_FLOAT_EQ(temporalDistanceWeight(5, 3), 0.25f);
  EXPECT_FLOAT_EQ(temporalNoiseWeight(2.0f, 2.0f), std::exp(-1.0f));
  EXPECT_FLOAT_EQ(temporalNoiseWeight(1.0f, 2.0f), std::exp(-0.25f));
  EXPECT_FLOAT_EQ(temporalNoiseWeight(0.0f, 0.0f), std::exp(-1.0f));
}

TEST(Kernel, BandwidthSamplesAreTheDocumentedCandidates)
{
  // Sample m is the m-th valid point with a finite normal in index order, m = rng() % candidates
  // with std::mt19937_64(seed); the bandwidths are the means of the sampled windows' largest
  // distance and height spread. Holes, and valid points without a normal, make the candidates
  // of a 256-point block (and of its 32-point chunks) uneven, so a wrong count shows.
  const Grid grid = randomSurface(90, 70, 0.2, 21);
  NormalField normals = estimateNormals(grid, 3, Viewpoint{0, 0, 0}, 1);
  for (std::size_t i = 0; i < grid.size(); i += 7)
    normals.nx[i] = std::numeric_limits<float>::quiet_NaN();
  const int samples = 300, r = 2;
  const std::uint64_t seed = 5;
  std::vector<int> candidates;
  for (std::size_t i = 0; i < grid.size(); ++i)
    if (grid.valid[i] && std::isfinite(normals.nx[i]))
      candidates.push_back(static_cast<int>(i));
  std::mt19937_64 rng(seed);
  std::vector<int> picks(samples);
  for (int& k : picks)
    k = candidates[rng() % candidates.size()];
  std::sort(picks.begin(), picks.end());
  double sum_extent = 0.0, sum_spread = 0.0;
  for (const int k : picks) {
    const int u = k % grid.width, v = k / grid.width;
    double max_dist2 = 0.0, sum_h = 0.0, sum_h2 = 0.0;
    int valid = 0;
    for (int jv = std::max(0, v - r); jv <= std::min(grid.height - 1, v + r); ++jv)
      for (int ju = std::max(0, u - r); ju <= std::min(grid.width - 1, u + r); ++ju) {
        const int j = jv * grid.width + ju;
        if (!grid.valid[j])
          continue;
        const double dx = double(grid.x[j]) - grid.x[k], dy = double(grid.y[j]) - grid.y[k];
        const double dz = double(grid.z[j]) - grid.z[k];
        max_dist2 = std::max(max_dist2, dx * dx + dy * dy + dz * dz);
        const double h = dx * normals.nx[k] + dy * normals.ny[k] + dz * normals.nz[k];
        sum_h += h, sum_h2 += h * h, ++valid;
      }
    const double mean = sum_h / valid;
    sum_extent += std::sqrt(max_dist2);
    sum_spread += std::sqrt(std::max(0.0, sum_h2 / valid - mean * mean));
  }
  const Bandwidths b = estimateBandwidths(grid, normals, 2 * r + 1, samples, seed);
  EXPECT_FLOAT_EQ(b.mu_d, static_cast<float>(sum_extent / samples));
  EXPECT_FLOAT_EQ(b.sigma_s, static_cast<float>(sum_spread / samples));
}

TEST(Kernel, BandwidthsAreDeterministicPerSeed)
{
  const Grid grid = randomSurface(40, 30, 0.05, 9);
  const NormalField normals = estimateNormals(grid, 3, Viewpoint{0, 0, 0}, 1);
  const Bandwidths a = estimateBandwidths(grid, normals, 7, 200, 1);
  const Bandwidths b = estimateBandwidths(grid, normals, 7, 200, 1);
  const Bandwidths c = estimateBandwidths(grid, normals, 7, 200, 2);
  EXPECT_EQ(a.mu_d, b.mu_d);
  EXPECT_EQ(a.sigma_s, b.sigma_s);
  EXPECT_NE(a.mu_d, c.mu_d);
  // noise 4 mm along the ray: the tangent-plane offsets (to noisy one-ring planes) spread by
  // about that much, inflated by the normal error
  EXPECT_GT(a.sigma_s, 0.003f);
  EXPECT_LT(a.sigma_s, 0.012f);
}

// applyOffsets along the line of sight (vectorized, every point computed and only the moving
// ones taking the result) against the scalar rule, point by point: the point stays on its ray
// from the viewpoint, steps t = -h / cos with |cos| >= min_cos, h and t within +/- limit; holes,
// zero, NaN and infinite offsets and the viewpoint itself leave the point as it is.
TEST(Kernel, LineOfSightDisplacementIsTheScalarRule)
{
  Grid grid = randomSurface(67, 23, 0.1, 41);
  const Viewpoint viewpoint{0.01f, -0.02f, 0.0f};
  const std::size_t n = grid.size();
  NormalField normals = estimateNormals(grid, 5, viewpoint, 1);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> offset(-0.02f, 0.02f), tilt(-1.0f, 1.0f);
  std::vector<float> offsets(n), limit(n);
  for (std::size_t i = 0; i < n; ++i) {
    offsets[i] = offset(rng);
    limit[i] = 0.01f * (1.0f + tilt(rng));
    if (i % 13 == 2) { // grazing normals: |cos| below min_cos
      const float a = tilt(rng);
      normals.nx[i] = std::cos(a), normals.ny[i] = std::sin(a), normals.nz[i] = 0.0f;
    }
  }
  offsets[5] = 0.0f;
  offsets[6] = std::numeric_limits<float>::quiet_NaN();
  offsets[7] = std::numeric_limits<float>::infinity();
  grid.x[8] = viewpoint[0], grid.y[8] = viewpoint[1], grid.z[8] = viewpoint[2], grid.valid[8] = 1;
  for (const bool clamped : {false, true}) {
    const float min_cos = 0.25f;
    Grid moved = grid;
    applyOffsets(moved, normals, offsets, Displacement::line_of_sight, viewpoint, clamped ? limit : std::vector<float>{},
                 min_cos);
    std::size_t moving = 0;
    for (std::size_t i = 0; i < n; ++i) {
      float h = offsets[i];
      if (clamped)
        h = std::clamp(h, -limit[i], limit[i]);
      float vx = grid.x[i] - viewpoint[0], vy = grid.y[i] - viewpoint[1], vz = grid.z[i] - viewpoint[2];
      const float len = std::sqrt(vx * vx + vy * vy + vz * vz);
      if (!grid.valid[i] || h == 0.0f || !std::isfinite(h) || !(len > 0.0f)) {
        if (grid.valid[i])
          EXPECT_TRUE(moved.x[i] == grid.x[i] && moved.y[i] == grid.y[i] && moved.z[i] == grid.z[i]) << i;
        continue;
      }
      vx /= len, vy /= len, vz /= len;
      float c = vx * normals.nx[i] + vy * normals.ny[i] + vz * normals.nz[i];
      if (std::fabs(c) < min_cos)
        c = c < 0.0f ? -min_cos : min_cos;
      float t = -h / c;
      if (clamped)
        t = std::clamp(t, -limit[i], limit[i]);
      EXPECT_EQ(moved.x[i], grid.x[i] + t * vx) << i;
      EXPECT_EQ(moved.y[i], grid.y[i] + t * vy) << i;
      EXPECT_EQ(moved.z[i], grid.z[i] + t * vz) << i;
      ++moving;
    }
    EXPECT_GT(moving, n / 2);
  }
}
