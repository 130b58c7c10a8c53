// The noise-correlation estimate behind the automatic dilation, the dilated passes (each phase
// filtered as a frame of its own) and the automatic displacement.
#include "frame_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

using namespace range_nlm;
using namespace range_nlm::test;

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
  stereo.stereo_correlation_length = 2.0;
  stereo.noise_scale = 0.5;
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(stereo).front().noisy)), 2); // 2 at 640 columns
  // Blobs of 6 px: the correlation length (about 4.4 px here), rounded, up to 4.
  stereo.stereo_correlation_length = 6.0;
  stereo.noise_scale = 1.0;
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(stereo).front().noisy)), 4);
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

TEST(NoiseCorrelation, CorrelationLengthGrowsWithTheNoisesCorrelationLength)
{
  // Independent noise: not correlated, length 0.
  const Grid iid = gridOf(renderSequence(planeScene("kinect", 640, 480)).front().noisy);
  EXPECT_EQ(noiseCorrelationLength(estimateNoiseCorrelation(iid), iid.width), 0.0f);
  // The stereo model's Gaussian correlation exp(-(l / L)^2) over 80 % of the variance: the
  // variance of the second differences doubles from lag 1 at 0.55-0.75 L.
  float previous = 0.0f;
  for (double length : {4.0, 6.0, 8.0}) {
    SceneOptions stereo = planeScene("stereo", 640, 480);
    stereo.stereo_correlation_length = length;
    const Grid g = gridOf(renderSequence(stereo).front().noisy);
    const float l = noiseCorrelationLength(estimateNoiseCorrelation(g), g.width);
    EXPECT_GT(l, 0.5 * length) << length;
    EXPECT_LT(l, 0.8 * length) << length;
    EXPECT_GT(l, previous) << length;
    previous = l;
  }
  // A curve given directly: variance 1 at lags 1 and 2, 3 at lag 3, 8 from lag 4 on: twice lag 1's
  // at lag 2.5.
  NoiseCorrelation c;
  const float variances[8] = {1.0f, 1.0f, 3.0f, 8.0f, 8.0f, 8.0f, 8.0f, 8.0f};
  for (int l = 0; l < 8; ++l)
    c.scale[l] = std::sqrt(variances[l]);
  EXPECT_NEAR(noiseCorrelationLength(c, 640), 2.5f, 1e-5f);
  // Where the plateau is less than twice lag 1's (most of the noise white): half of lag R's,
  // 1.1 here, between lags 1 and 2.
  const float whiter[8] = {1.0f, 1.2f, 2.2f, 2.2f, 2.2f, 2.2f, 2.2f, 2.2f};
  for (int l = 0; l < 8; ++l)
    c.scale[l] = std::sqrt(whiter[l]);
  EXPECT_NEAR(noiseCorrelationLength(c, 640), 1.5f, 1e-5f);
  // Not correlated (lag 1 at least half of lag R): 0.
  c.scale.fill(1.0f);
  EXPECT_EQ(noiseCorrelationLength(c, 640), 0.0f);
}

TEST(NoiseCorrelation, AutomaticDilationFollowsTheCorrelationLength)
{
  // Half the stereo model's noise (weak: under 3.25 footprints beyond the blobs) at 640 columns:
  // the dilation is the correlation length, rounded, from 2 up to 4.
  SceneOptions stereo = planeScene("stereo", 640, 480);
  stereo.noise_scale = 0.5;
  std::vector<int> k;
  for (double length : {2.0, 4.0, 8.0}) {
    stereo.stereo_correlation_length = length;
    k.push_back(automaticDilation(gridOf(renderSequence(stereo).front().noisy)));
  }
  EXPECT_EQ(k, (std::vector<int>{2, 3, 4}));
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

TEST(NoiseCorrelation, EachDoublingOfStrongNoiseDoublesTheAutomaticDilation)
{
  // Independent noise of about 1.7 pixel footprints at 1.5 m: contiguous windows; three times
  // as strong: dilation 2.
  SceneOptions iid = planeScene("kinect", 640, 480);
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(iid).front().noisy)), 1);
  iid.noise_scale = 3.0;
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(iid).front().noisy)), 2);
  // Each further doubling of the noise doubles it again, up to 4 at 640 columns.
  iid.noise_scale = 6.0;
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(iid).front().noisy)), 4);
  iid.noise_scale = 24.0;
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(iid).front().noisy)), 4);
  // Correlated noise: 2 at 640 columns, 4 when strong.
  SceneOptions stereo = planeScene("stereo", 640, 480);
  stereo.stereo_correlation_length = 2.0;
  stereo.noise_scale = 0.5;
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(stereo).front().noisy)), 2);
  stereo.noise_scale = 4.0;
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(stereo).front().noisy)), 4);
  // Blobs of 6 px (a correlation length of about 4.3 px): 4, and 6 where the noise is strong
  // enough for a second doubling, read at twice the correlation length (12 footprints at lag 8,
  // 7.9 at lag 4); once strong (6 footprints at lag 8): still 4.
  stereo.stereo_correlation_length = 6.0;
  EXPECT_EQ(automaticDilation(gridOf(renderSequence(stereo).front().noisy)), 6);
  stereo.noise_scale = 2.0;
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
  // A phase of dilated passes keeps s = similarity_scale * sigma (no patch spread there:
  // Workspace::correlated_input); a frame filtered on its own would take s from its patch spread.
  contiguous.similarity_spread = 0.0f;
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
/// `count` frames of the boxes scene with stereo noise and 5 % dropouts at 320 x 240: correlated
/// noise, holes and borders, which take the automatic dilated passes.
std::vector<Grid>
stereoBoxesWithHoles(int count)
{
  SceneOptions o = planeScene("stereo", 320, 240);
  o.scene = SceneType::boxes;
  o.dropout = 0.05;
  o.frames = count;
  std::vector<Grid> frames;
  for (const auto& frame : renderSequence(o))
    frames.push_back(gridOf(frame.noisy));
  return frames;
}
} // namespace

// The default configuration on a frame with correlated noise, holes and borders, which takes the
// automatic dilated passes: the same bits with 1, 2 and 3 threads, and again when the workspace
// (pre-smoothed copy, gates, maps, the phases' frames and workspace) is reused for a second frame
// and then the first again.
TEST(Dilation, DefaultRunIsTheSameForAnyThreadCountAndAReusedWorkspace)
{
  const std::vector<Grid> sequence = stereoBoxesWithHoles(2);
  const Grid &first = sequence[0], &second = sequence[1];
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

namespace
{
/// Counts the stages it sees begin.
class StageCounter : public StageObserver
{
public:
  void begin(Stage stage, int) override { ++counts[static_cast<int>(stage)]; }
  void end(Stage, int) override {}
  int count(Stage stage) const { return counts[static_cast<int>(stage)]; }

private:
  int counts[kStageCount] = {};
};
} // namespace

// With two threads and no stage observer the four phases of the dilated passes run side by side,
// one thread each, in workspaces of their own; with an observer (which must see each phase's
// stages in turn) they run one after the other with both threads. Both give the same bits: alone
// with a selection of points and the uncertainty (whose phase values are merged too), and as the
// middle frame of three, on a frame with holes and borders.
TEST(Dilation, PhasesSideBySideGiveTheBitsOfThePhasesInTurn)
{
  const std::vector<Grid> frames = stereoBoxesWithHoles(3);
  ASSERT_EQ(automaticDilation(frames[1]), 2);
  std::vector<unsigned char> active(frames[1].size(), 0);
  for (std::size_t i = 0; i < active.size(); i += 3)
    active[i] = 1;
  FilterParameters p = FilterParameters::recommended();
  p.threads = 2;
  FilterParameters with_uncertainty = p;
  with_uncertainty.uncertainty = true;
  struct Case
  {
    std::vector<const Grid*> frames;
    int center;
    const FilterParameters* parameters;
    const std::vector<unsigned char>* active;
  };
  const std::vector<unsigned char> all;
  const std::vector<Case> cases{{{&frames[1]}, 0, &with_uncertainty, &active},
                                {{&frames[0], &frames[1], &frames[2]}, 1, &p, &all}};
  for (const Case& c : cases) {
    StageCounter counter;
    FilterWorkspace in_turn, side_by_side;
    in_turn.setStageObserver(&counter);
    runFilter(c.frames, c.center, *c.parameters, kOrigin, *c.active, in_turn);
    runFilter(c.frames, c.center, *c.parameters, kOrigin, *c.active, side_by_side);
    // The observer saw the four phases' offsets and the last pass's.
    EXPECT_EQ(counter.count(Stage::offsets), 5) << c.frames.size() << " frames";
    EXPECT_TRUE(sameBits(in_turn.result().output, side_by_side.result().output)) << c.frames.size() << " frames";
    EXPECT_FALSE(sameBits(side_by_side.result().output, *c.frames[c.center])) << c.frames.size() << " frames";
    if (c.parameters->uncertainty) {
      ASSERT_EQ(in_turn.result().uncertainty.size(), side_by_side.result().uncertainty.size());
      EXPECT_EQ(0, std::memcmp(in_turn.result().uncertainty.data(), side_by_side.result().uncertainty.data(),
                               in_turn.result().uncertainty.size() * sizeof(float)));
    }
  }
}

// With one iteration (the live preset) the phases run side by side too, and the run reports the
// last phase's bandwidths and frame weights as the phases in turn do: output, uncertainty,
// bandwidths and weights the same bits, alone and as the newest frame of a window of two.
TEST(Dilation, OneIterationPhasesSideBySideGiveTheBitsAndBandwidthsOfThePhasesInTurn)
{
  const std::vector<Grid> frames = stereoBoxesWithHoles(2);
  ASSERT_EQ(automaticDilation(frames[1]), 2);
  FilterParameters p = FilterParameters::live();
  p.threads = 2;
  p.uncertainty = true;
  for (const std::vector<const Grid*>& window :
       {std::vector<const Grid*>{&frames[1]}, std::vector<const Grid*>{&frames[0], &frames[1]}}) {
    const int center = static_cast<int>(window.size()) - 1;
    StageCounter counter;
    FilterWorkspace in_turn, side_by_side;
    in_turn.setStageObserver(&counter);
    runFilter(window, center, p, kOrigin, {}, in_turn);
    runFilter(window, center, p, kOrigin, {}, side_by_side);
    EXPECT_EQ(counter.count(Stage::offsets), 4) << window.size() << " frames"; // the phases only
    const FilterRun &a = in_turn.result(), &b = side_by_side.result();
    EXPECT_TRUE(sameBits(a.output, b.output)) << window.size() << " frames";
    EXPECT_FALSE(sameBits(b.output, *window[center])) << window.size() << " frames";
    ASSERT_EQ(a.uncertainty.size(), b.uncertainty.size());
    EXPECT_EQ(0, std::memcmp(a.uncertainty.data(), b.uncertainty.data(), a.uncertainty.size() * sizeof(float)));
    ASSERT_EQ(a.bandwidths.size(), window.size());
    ASSERT_EQ(b.bandwidths.size(), window.size());
    for (std::size_t k = 0; k < window.size(); ++k) {
      EXPECT_EQ(a.bandwidths[k].distance, b.bandwidths[k].distance) << k;
      EXPECT_EQ(a.bandwidths[k].similarity, b.bandwidths[k].similarity) << k;
    }
    EXPECT_EQ(a.frame_weights, b.frame_weights) << window.size() << " frames";
  }
}
