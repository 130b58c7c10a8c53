// The noise-correlation estimate behind the automatic dilation, the dilated passes (each phase
// filtered as a frame of its own), the motion test of the guarded cross-frame bandwidths and the
// levelling of frames that differ by a drift along the rays.
#include "core/internal.h"

#include <range_nlm/core/pipeline.h>
#include <range_nlm/eval/synthetic_scene.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

using namespace range_nlm;

namespace
{
Grid
gridOf(const pcl::PointCloud<pcl::PointXYZ>& c)
{
  return Grid::fromInterleaved(reinterpret_cast<const float*>(c.points.data()), static_cast<int>(c.width),
                               static_cast<int>(c.height), sizeof(pcl::PointXYZ) / sizeof(float));
}

SceneOptions
planeScene(const char* noise, int width, int height, int frames = 1)
{
  SceneOptions o;
  o.width = width;
  o.height = height;
  o.fx = o.fy = 525.0 * width / 640;
  o.scene = SceneType::plane;
  o.plane_depth = 1.5;
  o.noise = noiseModelFromString(noise);
  o.frames = frames;
  o.seed = 11;
  return o;
}

const Viewpoint kOrigin{0.0f, 0.0f, 0.0f};

/// detail::alongNormals of b against a.
std::vector<float>
alongOf(const Grid& a, const NormalField& n, const Grid& b)
{
  std::vector<float> along;
  detail::alongNormals(a, n, b, 1, along);
  return along;
}
} // namespace

TEST(NoiseCorrelation, IndependentNoiseIsFlatOverLagsCorrelatedNoiseGrows)
{
  const Grid iid = gridOf(renderSequence(planeScene("kinect", 320, 240)).front().noisy);
  const NoiseCorrelation a = estimateNoiseCorrelation(iid);
  EXPECT_GT(a.samples, 1000u);
  // On a plane the second differences of 1/z are noise only: the same scale at every lag.
  for (float s : a.scale)
    EXPECT_NEAR(s / a.scale[0], 1.0, 0.1);

  SceneOptions stereo = planeScene("stereo", 320, 240);
  stereo.stereo_correlated_share = 0.9;
  stereo.stereo_correlation_length = 4.0;
  const NoiseCorrelation b = estimateNoiseCorrelation(gridOf(renderSequence(stereo).front().noisy));
  // Correlation length 4 px: at lag 1 the differences cancel most of the correlated part.
  EXPECT_LT(b.scale[0] * b.scale[0], 0.3f * b.scale[7] * b.scale[7]);
  for (int lag = 1; lag < 8; ++lag)
    EXPECT_GE(b.scale[lag], 0.95f * b.scale[lag - 1]) << lag;
}

TEST(NoiseCorrelation, AutomaticDilationIsOneForIndependentNoiseAndGrowsWithTheWidth)
{
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(planeScene("kinect", 640, 480)).front().noisy)), 1);
  SceneOptions stereo = planeScene("stereo", 640, 480);
  stereo.stereo_correlation_length = 6.0;
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(stereo).front().noisy)), 2); // 2 at 640 columns
  SceneOptions wide = planeScene("stereo", 1280, 720);
  wide.stereo_correlation_length = 8.0;
  wide.stereo_correlated_share = 0.9;
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(wide).front().noisy)), 4); // 4 at 1280 columns
  // The boxes scene without noise at 200 x 150: its edges and curvature alone do not look like
  // correlated noise at the short lags used there.
  SceneOptions small = planeScene("laser", 200, 150);
  small.scene = SceneType::boxes;
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(small).front().noisy)), 1);
  // No valid point: nothing to estimate, contiguous windows.
  Grid empty(64, 48);
  EXPECT_EQ(automaticDilation(empty), 1);
}

TEST(NoiseCorrelation, ScaleInFootprintsIsTheScaleOverTheDistanceBetweenRays)
{
  // A fronto-parallel plane: every pixel's footprint is z / fx, the same at every lag.
  const SceneOptions o = planeScene("kinect", 320, 240);
  const NoiseCorrelation c = estimateNoiseCorrelation(gridOf(renderSequence(o).front().noisy));
  const double footprint = o.plane_depth / o.fx;
  for (int lag = 1; lag <= 8; ++lag) {
    ASSERT_GT(c.scale[lag - 1], 0.0f) << lag;
    EXPECT_NEAR(c.scale_in_footprints[lag - 1] * footprint / c.scale[lag - 1], 1.0, 0.03) << lag;
  }
  // Twice the noise, twice the footprints.
  SceneOptions louder = o;
  louder.noise_scale = 2.0;
  const NoiseCorrelation d = estimateNoiseCorrelation(gridOf(renderSequence(louder).front().noisy));
  EXPECT_NEAR(d.scale_in_footprints[3] / c.scale_in_footprints[3], 2.0, 0.1);
  // A frame without valid points has nothing to measure.
  EXPECT_EQ(estimateNoiseCorrelation(Grid(64, 48)).scale_in_footprints[3], 0.0f);
}

TEST(NoiseCorrelation, StrongNoiseDoublesTheAutomaticDilation)
{
  // Independent noise of about 1.7 pixel footprints at 1.5 m: contiguous windows; three times
  // as strong: dilation 2.
  SceneOptions iid = planeScene("kinect", 640, 480);
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(iid).front().noisy)), 1);
  iid.noise_scale = 3.0;
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(iid).front().noisy)), 2);
  // Correlated noise: 2 at 640 columns, 4 when strong.
  SceneOptions stereo = planeScene("stereo", 640, 480);
  stereo.stereo_correlation_length = 6.0;
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(stereo).front().noisy)), 2);
  stereo.noise_scale = 4.0;
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(stereo).front().noisy)), 4);
}

TEST(Dilation, EachPhaseIsFilteredAsAFrameOfItsOwn)
{
  SceneOptions o = planeScene("stereo", 61, 47); // odd sizes: phases of different sizes
  o.scene = SceneType::boxes;
  o.dropout = 0.05;
  const Grid frame = gridOf(renderSequence(o).front().noisy);
  FilterParameters p = FilterParameters::recommended();
  p.iterations = 1;
  p.search_window = 5;
  p.dilation = 2;
  const FilterRun dilated = runFilter({&frame}, 0, p, kOrigin, {});

  FilterParameters contiguous = p;
  contiguous.dilation = 1;
  Grid expected = frame;
  for (int v0 = 0; v0 < 2; ++v0)
    for (int u0 = 0; u0 < 2; ++u0) {
      const int w = (frame.width - u0 + 1) / 2, h = (frame.height - v0 + 1) / 2;
      Grid phase(w, h);
      for (int b = 0; b < h; ++b)
        for (int a = 0; a < w; ++a) {
          const std::size_t from = static_cast<std::size_t>(v0 + 2 * b) * frame.width + u0 + 2 * a, to = b * w + a;
          phase.x[to] = frame.x[from], phase.y[to] = frame.y[from], phase.z[to] = frame.z[from];
          phase.valid[to] = frame.valid[from];
        }
      const FilterRun out = runFilter({&phase}, 0, contiguous, kOrigin, {});
      for (int b = 0; b < h; ++b)
        for (int a = 0; a < w; ++a) {
          const std::size_t to = static_cast<std::size_t>(v0 + 2 * b) * frame.width + u0 + 2 * a, from = b * w + a;
          expected.x[to] = out.output.x[from], expected.y[to] = out.output.y[from];
          expected.z[to] = out.output.z[from];
        }
    }
  ASSERT_EQ(dilated.output.size(), expected.size());
  std::size_t moved = 0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(dilated.output.valid[i], frame.valid[i]) << i;
    if (!frame.valid[i])
      continue;
    EXPECT_EQ(dilated.output.z[i], expected.z[i]) << i;
    EXPECT_EQ(dilated.output.x[i], expected.x[i]) << i;
    moved += dilated.output.z[i] != frame.z[i];
  }
  EXPECT_GT(moved, expected.size() / 2);

  // With two passes the last one runs with contiguous windows on the whole frame.
  p.iterations = 2;
  const FilterRun two = runFilter({&frame}, 0, p, kOrigin, {});
  FilterParameters last = contiguous;
  last.iterations = 1;
  const FilterRun expected_two = runFilter({&dilated.output}, 0, last, kOrigin, {});
  for (std::size_t i = 0; i < expected.size(); ++i)
    if (frame.valid[i])
      EXPECT_EQ(two.output.z[i], expected_two.output.z[i]) << i;
}

TEST(Displacement, AutomaticIsAlongTheLineOfSightWithOtherFramesAndAlongTheNormalAlone)
{
  SceneOptions o = planeScene("kinect", 80, 60, 3);
  o.scene = SceneType::boxes;
  const auto seq = renderSequence(o);
  std::vector<Grid> grids;
  for (const auto& f : seq)
    grids.push_back(gridOf(f.noisy));
  const std::vector<const Grid*> three{&grids[0], &grids[1], &grids[2]}, one{&grids[1]};
  auto run = [&](const std::vector<const Grid*>& frames, int center, Displacement d) {
    FilterParameters p = FilterParameters::recommended();
    p.displacement = d;
    return runFilter(frames, center, p, kOrigin, {}).output;
  };
  // Bit for bit (invalid points are NaN, which == would call different).
  auto same = [](const Grid& a, const Grid& b) {
    auto bits = [](const std::vector<float>& u, const std::vector<float>& v) {
      return u.size() == v.size() && std::memcmp(u.data(), v.data(), u.size() * sizeof(float)) == 0;
    };
    return bits(a.x, b.x) && bits(a.y, b.y) && bits(a.z, b.z);
  };
  ASSERT_EQ(FilterParameters().displacement, Displacement::automatic);
  EXPECT_EQ(FilterParameters::paper().displacement, Displacement::normal);
  const Grid temporal = run(three, 1, Displacement::automatic);
  EXPECT_TRUE(same(temporal, run(three, 1, Displacement::line_of_sight)));
  EXPECT_FALSE(same(temporal, run(three, 1, Displacement::normal)));
  const Grid alone = run(one, 0, Displacement::automatic);
  EXPECT_TRUE(same(alone, run(one, 0, Displacement::normal)));
  EXPECT_FALSE(same(alone, run(one, 0, Displacement::line_of_sight)));
  // An all-NaN neighbour takes no part: the frame is filtered as alone.
  Grid empty(80, 60);
  EXPECT_TRUE(same(run({&grids[1], &empty}, 0, Displacement::automatic), alone));
}

TEST(Dilation, IsRefusedBelowZeroAndPaperKeepsContiguousWindows)
{
  FilterParameters p;
  p.dilation = -1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  EXPECT_EQ(FilterParameters::paper().dilation, 1);
  EXPECT_EQ(FilterParameters::recommended().dilation, 0);
}

TEST(FramesMoved, NoiseIsNotMotionAShiftIs)
{
  SceneOptions o = planeScene("stereo", 320, 240, 2);
  o.scene = SceneType::boxes;
  const auto seq = renderSequence(o);
  const Grid a = gridOf(seq[0].noisy), b = gridOf(seq[1].noisy);
  const NormalField n = estimateNormals(a, 7, kOrigin, 0);
  // A static scene with fresh correlated noise in each frame: not moved.
  EXPECT_FALSE(framesMoved(a, n, b));
  // The camera 40 mm closer (about twice this sensor's noise at these ranges): every point 40 mm
  // nearer along its ray.
  Grid closer = b;
  for (std::size_t i = 0; i < closer.size(); ++i) {
    const float len = std::sqrt(closer.x[i] * closer.x[i] + closer.y[i] * closer.y[i] + closer.z[i] * closer.z[i]);
    const float f = (len - 0.040f) / len;
    closer.x[i] *= f, closer.y[i] *= f, closer.z[i] *= f;
  }
  EXPECT_TRUE(framesMoved(a, n, closer));
  // Too few blocks to tell: not moved.
  Grid tiny(16, 12);
  EXPECT_FALSE(framesMoved(tiny, estimateNormals(tiny, 3, kOrigin, 0), tiny));
}

namespace
{
/// `g` with every valid point moved along its ray (from the origin) by offset(u) metres.
template <typename Offset>
Grid
alongRays(Grid g, Offset offset)
{
  for (int v = 0; v < g.height; ++v)
    for (int u = 0; u < g.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * g.width + u;
      const float len = std::sqrt(g.x[i] * g.x[i] + g.y[i] * g.y[i] + g.z[i] * g.z[i]);
      if (!g.valid[i] || !(len > 0.0f))
        continue;
      const float f = (len + offset(u)) / len;
      g.x[i] *= f, g.y[i] *= f, g.z[i] *= f;
    }
  return g;
}

float
rangeOf(const Grid& g, std::size_t i)
{
  return std::sqrt(g.x[i] * g.x[i] + g.y[i] * g.y[i] + g.z[i] * g.z[i]);
}
} // namespace

// A depth camera that stands still may see its whole depth map drift from frame to frame by
// more than its noise, slowly varying over the image (active stereo); a camera that moves shifts
// the image's structure too. Only the latter is motion.
TEST(FrameChange, NoiseIsNoneADriftAlongTheRaysIsAnOffsetAShiftIsMotion)
{
  SceneOptions o = planeScene("stereo", 320, 240, 2);
  o.scene = SceneType::boxes;
  const auto seq = renderSequence(o);
  const Grid a = gridOf(seq[0].noisy), b = gridOf(seq[1].noisy);
  const float w = static_cast<float>(a.width);
  // Fresh correlated noise in each frame of a static scene: no change.
  const FrameOffset noise = analyseFrameChange(a, b, kOrigin);
  EXPECT_EQ(noise.change, FrameChange::none);
  EXPECT_TRUE(noise.range_offset.empty());
  // The depth 40 to 60 mm farther, growing across the image: an offset, and the field follows it.
  const auto drift = [w](int u) { return 0.040f + 0.020f * u / w; };
  const Grid drifted = alongRays(b, drift);
  const FrameOffset offset = analyseFrameChange(a, drifted, kOrigin);
  ASSERT_EQ(offset.change, FrameChange::offset);
  ASSERT_EQ(offset.range_offset.size(), a.size());
  std::vector<float> errors;
  for (int v = 0; v < a.height; ++v)
    for (int u = 0; u < a.width; ++u)
      errors.push_back(std::fabs(offset.range_offset[static_cast<std::size_t>(v) * a.width + u] - drift(u)));
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.003f);
  const std::size_t row = static_cast<std::size_t>(a.height / 2) * a.width;
  EXPECT_GT(offset.range_offset[row + a.width - 1] - offset.range_offset[row], 0.012f);
  // The same drift with the image shifted by 3 pixels along the rows (the camera turned): motion.
  Grid turned(a.width, a.height);
  for (int v = 0; v < a.height; ++v)
    for (int u = 3; u < a.width; ++u) {
      const std::size_t to = static_cast<std::size_t>(v) * a.width + u, from = to - 3;
      turned.x[to] = drifted.x[from], turned.y[to] = drifted.y[from], turned.z[to] = drifted.z[from];
      turned.valid[to] = drifted.valid[from];
    }
  EXPECT_EQ(analyseFrameChange(a, turned, kOrigin).change, FrameChange::motion);
  // Blocks of 64 pixels alternately 150 mm farther and not: no smooth drift explains them (an
  // object moved against the rest), so motion, although nothing moved across the image.
  const Grid far = alongRays(b, [](int) { return 0.150f; });
  Grid patches = b;
  for (int v = 0; v < a.height; ++v)
    for (int u = 0; u < a.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * a.width + u;
      if ((u / 64 + v / 64) % 2 == 0)
        patches.x[i] = far.x[i], patches.y[i] = far.y[i], patches.z[i] = far.z[i];
    }
  EXPECT_EQ(analyseFrameChange(a, patches, kOrigin).change, FrameChange::motion);
  // Too few blocks (20 at 40 x 32) to tell a drift from blocks that moved: motion.
  SceneOptions tiny = planeScene("kinect", 40, 32, 2);
  const auto small = renderSequence(tiny);
  EXPECT_EQ(analyseFrameChange(gridOf(small[0].noisy), alongRays(gridOf(small[1].noisy), drift), kOrigin).change,
            FrameChange::motion);
  EXPECT_EQ(analyseFrameChange(a, a, kOrigin).change, FrameChange::none);
  for (int threads : {2, 3}) {
    const FrameOffset t = detail::analyseFrameChange(a, drifted, kOrigin, threads);
    EXPECT_EQ(t.change, offset.change) << threads;
    EXPECT_EQ(t.range_offset, offset.range_offset) << threads;
    EXPECT_EQ(detail::analyseFrameChange(a, turned, kOrigin, threads).change, FrameChange::motion) << threads;
  }
}

// Three frames of a static camera whose depth drifts by +45...+55, +15 and -60...-70 mm (mean 0):
// the default brings them to their mean level and filters the current frame there, close to the
// truth, where the paper's cross-frame bandwidths keep its +15 mm.
TEST(FrameChange, TemporalRunAveragesTheDriftOfAStaticCamera)
{
  SceneOptions o = planeScene("stereo", 320, 240, 3);
  o.scene = SceneType::boxes;
  const auto seq = renderSequence(o);
  const float w = static_cast<float>(o.width);
  const Grid f0 = alongRays(gridOf(seq[0].noisy), [w](int u) { return 0.045f + 0.010f * u / w; });
  const Grid f1 = alongRays(gridOf(seq[1].noisy), [](int) { return 0.015f; });
  const Grid f2 = alongRays(gridOf(seq[2].noisy), [w](int u) { return -0.060f - 0.010f * u / w; });
  ASSERT_EQ(analyseFrameChange(f1, f0, kOrigin).change, FrameChange::offset);
  ASSERT_EQ(analyseFrameChange(f1, f2, kOrigin).change, FrameChange::offset);
  const auto& truth = seq[1].truth;
  // Median of the signed range error of the filtered current frame against the truth.
  const auto medianError = [&](const FilterParameters& p) {
    const FilterRun run = runFilter({&f0, &f1, &f2}, 1, p, kOrigin, {});
    std::vector<float> errors;
    for (std::size_t i = 0; i < run.output.size(); ++i) {
      const pcl::PointNormal& t = truth.points[i];
      if (run.output.valid[i] && std::isfinite(t.z))
        errors.push_back(rangeOf(run.output, i) - std::sqrt(t.x * t.x + t.y * t.y + t.z * t.z));
    }
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    return errors[errors.size() / 2];
  };
  FilterParameters p = FilterParameters::recommended();
  EXPECT_LT(std::fabs(medianError(p)), 0.003f);
  p.cross_frame_bandwidth = CrossFrameBandwidth::spatial;
  EXPECT_GT(medianError(p), 0.010f);
}

TEST(Dilation, AutomaticFallsBackToContiguousWindowsWhereAPhaseIsNarrowerThanTheWindows)
{
  // A plane at 1 m with a smooth ripple of period 6 px: its second differences at lag 2 are 3
  // times those at lag 1, so automaticDilation flags it as correlated.
  const int w = 16, h = 40;
  Grid g(w, h);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * w + u;
      const float z = 1.0f + 0.004f * std::sin(6.2832f * u / 6.0f + 0.3f) * std::sin(6.2832f * v / 6.0f + 1.1f);
      g.x[i] = (u - w / 2) * z / 500.0f, g.y[i] = (v - h / 2) * z / 500.0f, g.z[i] = z;
      g.valid[i] = 1;
    }
  ASSERT_EQ(automaticDilation(g), 2);
  FilterParameters automatic = FilterParameters::recommended(), contiguous = automatic;
  contiguous.dilation = 1;
  // Phases of 8 columns cannot hold the 9 x 9 window: the default runs contiguous windows.
  const FilterRun a = runFilter({&g}, 0, automatic, kOrigin, {});
  const FilterRun b = runFilter({&g}, 0, contiguous, kOrigin, {});
  EXPECT_EQ(a.output.z, b.output.z);
  // Asked for explicitly, the dilation is refused with the window that does not fit.
  FilterParameters forced = automatic;
  forced.dilation = 2;
  EXPECT_THROW(runFilter({&g}, 0, forced, kOrigin, {}), std::invalid_argument);
}

namespace
{
/// Whether two grids hold the same bits in every coordinate and flag.
bool
sameBits(const Grid& a, const Grid& b)
{
  return a.width == b.width && a.height == b.height && a.valid == b.valid &&
         std::memcmp(a.x.data(), b.x.data(), a.x.size() * sizeof(float)) == 0 &&
         std::memcmp(a.y.data(), b.y.data(), a.y.size() * sizeof(float)) == 0 &&
         std::memcmp(a.z.data(), b.z.data(), a.z.size() * sizeof(float)) == 0;
}
} // namespace

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

// The default configuration on a frame with correlated noise, holes and borders, which takes the
// automatic dilated passes: the same bits with 1, 2 and 3 threads, and again when the workspace
// (pre-smoothed copy, gates, maps, the phases' frames and workspace) is reused for a second frame
// and then the first again.
TEST(Dilation, DefaultRunIsTheSameForAnyThreadCountAndAReusedWorkspace)
{
  SceneOptions o = planeScene("stereo", 320, 240);
  o.scene = SceneType::boxes;
  o.dropout = 0.05;
  o.frames = 2;
  const auto sequence = renderSequence(o);
  const Grid first = gridOf(sequence[0].noisy), second = gridOf(sequence[1].noisy);
  ASSERT_EQ(automaticDilation(first), 2);
  FilterParameters p = FilterParameters::recommended();
  p.threads = 1;
  const FilterRun reference = runFilter({&first}, 0, p, kOrigin, {});
  const FilterRun other = runFilter({&second}, 0, p, kOrigin, {});
  EXPECT_FALSE(sameBits(reference.output, first)); // it moved points
  for (int threads : {1, 2, 3}) {
    p.threads = threads;
    FilterWorkspace workspace;
    for (const Grid* g : {&first, &second, &first}) {
      runFilter({g}, 0, p, kOrigin, {}, workspace);
      EXPECT_TRUE(sameBits(workspace.result().output, g == &first ? reference.output : other.output))
          << threads << " threads";
    }
  }
}

// The per-pixel test of change: frames differing by noise (however correlated, its frame-to-frame
// ratio given) mark almost nothing; a region moved 150 mm along the rays (about 10 x the noise of
// the stereo frame at this size, 30 x the kinect's) is marked inside and up to
// a pixel beyond its border (3 x 3 majority; tilted normal estimates of the strong stereo noise miss some), the rest not;
// holes in either frame are not changed;
// any thread count gives the same marks.
TEST(FrameChange, PerPixelTestMarksWhatMovedBeyondTheNoiseAndNotTheNoise)
{
  for (const char* noise : {"kinect", "stereo"}) {
    SceneOptions o = planeScene(noise, 160, 120, 2);
    o.dropout = 0.05;
    const auto seq = renderSequence(o);
    const Grid a = gridOf(seq[0].noisy), b = gridOf(seq[1].noisy);
    const NormalField n = estimateNormals(a, 7, kOrigin, 1);
    const NoiseProfile profile = estimateNoiseProfile(b, 9, 1000, 3, kOrigin);
    std::vector<float> rho(a.size()), sigma(a.size());
    for (std::size_t i = 0; i < a.size(); ++i)
      rho[i] = a.valid[i] ? std::sqrt(a.x[i] * a.x[i] + a.y[i] * a.y[i] + a.z[i] * a.z[i]) : 0.0f;
    detail::interpolateProfile(profile.range, profile.sigma, rho.data(), sigma.data(), a.size());
    const float ratio = std::max(1.0f, estimateTemporalNoiseRatio(a, n, b, profile, kOrigin));
    std::vector<unsigned char> changed;
    detail::markChangedPixels(alongOf(a, n, b), a.width, a.height, sigma.data(), sigma.data(), ratio, 1, changed);
    ASSERT_EQ(changed.size(), a.size());
    const auto count = [](const std::vector<unsigned char>& c) { return std::count(c.begin(), c.end(), 1); };
    EXPECT_LT(count(changed), static_cast<long>(a.size() / 200)) << noise << " ratio " << ratio;

    // Rows 40..79, columns 50..109 of b moved 150 mm away along the rays.
    Grid moved = b;
    for (int v = 40; v < 80; ++v)
      for (int u = 50; u < 110; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * b.width + u;
        const float len = std::sqrt(b.x[i] * b.x[i] + b.y[i] * b.y[i] + b.z[i] * b.z[i]);
        const float f = (len + 0.15f) / len;
        moved.x[i] *= f, moved.y[i] *= f, moved.z[i] *= f;
      }
    detail::markChangedPixels(alongOf(a, n, moved), a.width, a.height, sigma.data(), sigma.data(), ratio, 1, changed);
    long inside = 0, outside = 0;
    for (int v = 0; v < a.height; ++v)
      for (int u = 0; u < a.width; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * a.width + u;
        const bool in = v >= 41 && v < 79 && u >= 51 && u < 109, near = v >= 39 && v < 81 && u >= 49 && u < 111;
        if (in)
          inside += changed[i];
        else if (!near)
          outside += changed[i];
      }
    EXPECT_GT(inside, 38 * 58 * 80 / 100) << noise << " ratio " << ratio; // kinect 99 %, stereo 89 % // the holes' pixels mostly follow their neighbours
    EXPECT_LT(outside, static_cast<long>(a.size() / 200)) << noise;
    for (int threads : {2, 3}) {
      std::vector<unsigned char> again;
      detail::markChangedPixels(alongOf(a, n, moved), a.width, a.height, sigma.data(), sigma.data(), ratio, threads, again);
      EXPECT_EQ(again, changed) << threads;
    }
    // The larger of the two frames' noise sets the threshold (a smoothed neighbour, whose own
    // noise is small, is still compared at the current frame's): 150 mm is within 3 x 100 mm.
    const std::vector<float> loud(a.size(), 0.1f);
    detail::markChangedPixels(alongOf(a, n, moved), a.width, a.height, loud.data(), sigma.data(), 1.0f, 1, changed);
    EXPECT_EQ(count(changed), 0) << noise;
    // A pixel invalid in either frame has no say; all invalid: nothing changed.
    Grid empty = moved;
    std::fill(empty.valid.begin(), empty.valid.end(), 0);
    detail::markChangedPixels(alongOf(a, n, empty), a.width, a.height, sigma.data(), sigma.data(), ratio, 1, changed);
    EXPECT_EQ(count(changed), 0);
  }
}

// The patch guide's margin: widenMask sets every pixel within the radius (Chebyshev) of a set
// pixel and no other, clipped at the frame's border, for any thread count; radius 0 copies.
TEST(FrameChange, WidenedMaskIsTheSetPixelsSquareNeighbourhood)
{
  const int w = 29, h = 17;
  std::vector<unsigned char> mask(w * h, 0);
  mask[5 * w + 7] = 1;   // inside
  mask[0 * w + 28] = 1;  // a corner
  mask[16 * w + 1] = 1;  // near another corner
  std::vector<unsigned char> out;
  detail::widenMask(mask, w, h, 2, 1, out);
  ASSERT_EQ(out.size(), mask.size());
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      bool expected = false;
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
          expected |= mask[y * w + x] && std::abs(x - u) <= 2 && std::abs(y - v) <= 2;
      EXPECT_EQ(out[v * w + u], expected ? 1 : 0) << u << ", " << v;
    }
  for (int threads : {2, 3}) {
    std::vector<unsigned char> again;
    detail::widenMask(mask, w, h, 2, threads, again);
    EXPECT_EQ(again, out) << threads;
  }
  detail::widenMask(mask, w, h, 0, 1, out);
  EXPECT_EQ(out, mask);
}

// The histogram median (the ranges' median of every run, the frame-to-frame noise ratio) is the
// value std::nth_element puts at rank count / 2, skipping negative, NaN and masked values; with
// ties (a quantized depth unit), values sharing one histogram bin and the count, for any thread
// count.
TEST(Median, HistogramMedianIsTheNthElementOfTheCountedValues)
{
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(1.5f, 0.4f);
  for (std::size_t n : {1u, 2u, 7u, 1000u, 307200u}) {
    for (int quantized = 0; quantized < 2; ++quantized) {
      std::vector<float> values(n);
      std::vector<unsigned char> mask(n);
      for (std::size_t i = 0; i < n; ++i) {
        float v = noise(rng);
        if (quantized)
          v = std::round(v * 1000.0f) / 1000.0f; // many equal values, neighbours in one bin
        if (i % 11 == 3)
          v = -v;
        if (i % 17 == 5)
          v = std::numeric_limits<float>::quiet_NaN();
        values[i] = v;
        mask[i] = i % 5 != 1;
      }
      for (const unsigned char* m : {static_cast<const unsigned char*>(nullptr),
                                     static_cast<const unsigned char*>(mask.data())}) {
        std::vector<float> counted;
        for (std::size_t i = 0; i < n; ++i)
          if ((!m || m[i]) && values[i] >= 0.0f)
            counted.push_back(values[i]);
        for (int threads : {1, 2, 3}) {
          std::size_t count = 12345;
          const float median = detail::medianOfNonNegative(values.data(), m, n, threads, &count);
          ASSERT_EQ(count, counted.size()) << n;
          if (counted.empty()) {
            EXPECT_TRUE(std::isnan(median)) << n;
            continue;
          }
          std::vector<float> sorted = counted;
          std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
          EXPECT_EQ(median, sorted[sorted.size() / 2]) << n << " quantized " << quantized << " threads " << threads;
        }
      }
    }
  }
  const std::vector<float> none = {-1.0f, std::numeric_limits<float>::quiet_NaN(), -0.5f};
  std::size_t count = 7;
  EXPECT_TRUE(std::isnan(detail::medianOfNonNegative(none.data(), nullptr, none.size(), 2, &count)));
  EXPECT_EQ(count, 0u);
}


// The temporal filter's motion test and frame-to-frame noise ratio run on several threads: the
// same answers as one thread; and the temporal default (radius 1, guarded cross-frame bandwidths,
// automatic dilation) gives the same bits with 1, 2 and 3 threads, with holes and borders.
TEST(FramesMoved, MotionTestNoiseRatioAndTemporalRunDoNotDependOnTheThreadCount)
{
  SceneOptions o = planeScene("stereo", 320, 240, 3);
  o.scene = SceneType::boxes;
  o.dropout = 0.05;
  const auto seq = renderSequence(o);
  const Grid a = gridOf(seq[1].noisy), b = gridOf(seq[0].noisy), c = gridOf(seq[2].noisy);
  const NormalField n = estimateNormals(a, 7, kOrigin, 1);
  const NoiseProfile profile = estimateNoiseProfile(b, 9, 1000, 7, kOrigin);
  Grid closer = b;
  for (std::size_t i = 0; i < closer.size(); ++i)
    closer.z[i] -= 0.04f;
  const float ratio = estimateTemporalNoiseRatio(a, n, b, profile, kOrigin);
  EXPECT_GT(ratio, 0.0f);
  for (int threads : {2, 3}) {
    EXPECT_EQ(detail::framesMoved(a, n, b, threads), framesMoved(a, n, b)) << threads;
    EXPECT_EQ(detail::framesMoved(a, n, closer, threads), framesMoved(a, n, closer)) << threads;
    EXPECT_EQ(detail::estimateTemporalNoiseRatio(a, n, b, profile, kOrigin, threads), ratio) << threads;
  }
  FilterParameters p = FilterParameters::recommended();
  p.threads = 1;
  const FilterRun one = runFilter({&b, &a, &c}, 1, p, kOrigin, {});
  EXPECT_FALSE(sameBits(one.output, a));
  for (int threads : {2, 3}) {
    p.threads = threads;
    EXPECT_TRUE(sameBits(runFilter({&b, &a, &c}, 1, p, kOrigin, {}).output, one.output)) << threads << " threads";
  }
}

// The noise correlation's statistic: the mean of the smallest 80 % of the values, found by a
// histogram of their upper bits, is that of a full sort, with ties across the cut (a quantized
// depth unit), zeros, values spread over many octaves and sizes down to 0 and 1.
TEST(NoiseCorrelation, RobustMeanIsTheMeanOfTheSmallestFourFifths)
{
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (std::size_t n : {0u, 1u, 2u, 5u, 64u, 1000u, 38411u})
    for (int kind = 0; kind < 3; ++kind) {
      std::vector<float> values(n);
      for (float& v : values) {
        const float u = unit(rng);
        v = kind == 0   ? std::exp2(40.0f * u - 30.0f)                  // octaves 2^-30 .. 2^10
            : kind == 1 ? 0.001f * std::floor(u * 8.0f)                   // 8 steps, ties at the cut
                        : (unit(rng) < 0.3f ? 0.0f : 0.004f + 0.001f * u); // zeros and a narrow band
      }
      std::vector<float> sorted = values;
      std::sort(sorted.begin(), sorted.end());
      const std::size_t keep = n * 4 / 5;
      double sum = 0.0;
      for (std::size_t i = 0; i < keep; ++i)
        sum += sorted[i];
      const float expected = keep == 0 ? 0.0f : static_cast<float>(sum / keep);
      std::vector<float> work = values;
      EXPECT_FLOAT_EQ(detail::robustMean(work), expected) << "n " << n << " kind " << kind;
    }
}

