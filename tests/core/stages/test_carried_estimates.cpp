// Estimates carried in a stream (src/core/stages/carried_estimates.cpp,
// FilterParameters::reuse_estimates): a static stream reuses its noise profile and automatic
// dilation (the dilation stage no longer runs), a frame whose sensor noise or ranges changed gets
// fresh estimates and then the output of a fresh stream, and the outputs do not depend on the
// thread count.
#include "../frame_fixtures.h"
#include "core/stages/stages.h"

#include <range_nlm/parameters.h>

#include <gtest/gtest.h>

#include <map>
#include <vector>

using namespace range_nlm;
using namespace range_nlm::test;

namespace
{

/// Counts the stages a run begins.
class StageCounter : public StageObserver
{
public:
  void begin(Stage stage, int) override { ++begun[stage]; }
  void end(Stage, int) override {}
  std::map<Stage, int> begun;
};

/// Frames of the generated boxes scene (VGA's quarter) with fresh noise per frame.
std::vector<Grid>
sequence(const char* noise, int frames, double scale = 1.0, std::uint64_t seed = 5)
{
  SceneOptions o = planeScene(noise, 160, 120, frames);
  o.scene = SceneType::boxes;
  o.noise_scale = scale;
  o.seed = seed;
  std::vector<Grid> out;
  for (const SyntheticFrame& f : renderSequence(o))
    out.push_back(gridOf(f.noisy));
  return out;
}

FilterParameters
live(int threads = 2)
{
  FilterParameters p = FilterParameters::live();
  p.threads = threads;
  return p;
}

/// Filters `frames` in order through one workspace; per frame the output and whether the estimates
/// were reused, and how often the dilation stage ran.
struct StreamRun
{
  std::vector<Grid> outputs;
  std::vector<bool> reused;
  int dilation_stages = 0;
};

StreamRun
runStream(const std::vector<Grid>& frames, const FilterParameters& p)
{
  FilterWorkspace workspace;
  StageCounter counter;
  workspace.setStageObserver(&counter);
  StreamRun run;
  for (const Grid& frame : frames) {
    runFilter({&frame}, 0, p, kOrigin, {}, workspace);
    run.outputs.push_back(workspace.result().output);
    run.reused.push_back(workspace.result().estimates_reused);
  }
  run.dilation_stages = counter.begun[Stage::dilation];
  return run;
}

Grid
freshOutput(const Grid& frame, const FilterParameters& p)
{
  return runFilter({&frame}, 0, p, kOrigin, {}).output;
}

} // namespace

TEST(CarriedEstimates, TheLivePresetCarriesThem)
{
  EXPECT_TRUE(FilterParameters::live().reuse_estimates);
  EXPECT_FALSE(FilterParameters::recommended().reuse_estimates);
  EXPECT_FALSE(FilterParameters::paper().reuse_estimates);
}

// Fresh noise on the same scene and sensor: every frame after the first reuses the first frame's
// estimates, and the automatic dilation is estimated once.
TEST(CarriedEstimates, AStaticStreamReusesItsEstimates)
{
  for (const char* noise : {"kinect", "stereo"}) {
    const std::vector<Grid> frames = sequence(noise, 5);
    const StreamRun run = runStream(frames, live());
    EXPECT_EQ(run.reused, (std::vector<bool>{false, true, true, true, true})) << noise;
    EXPECT_EQ(run.dilation_stages, 1) << noise;
    // The first frame's output is a fresh run's; the others differ from a fresh run only through
    // the carried estimates.
    EXPECT_TRUE(sameBits(run.outputs[0], freshOutput(frames[0], live()))) << noise;
  }
}

// Without reuse_estimates nothing is carried: every frame is a fresh run.
TEST(CarriedEstimates, WithoutReuseEveryFrameIsAFreshRun)
{
  const std::vector<Grid> frames = sequence("kinect", 3);
  FilterParameters p = live();
  p.reuse_estimates = false;
  const StreamRun run = runStream(frames, p);
  EXPECT_EQ(run.reused, (std::vector<bool>{false, false, false}));
  EXPECT_EQ(run.dilation_stages, 3);
  for (std::size_t k = 0; k < frames.size(); ++k)
    EXPECT_TRUE(sameBits(run.outputs[k], freshOutput(frames[k], p))) << k;
}

// The sensor changes mid-way (a noise four times stronger, then correlated stereo noise): the frame
// after the change gets fresh estimates, so that its output is exactly a fresh stream's, and the
// frames after it reuse the new ones.
TEST(CarriedEstimates, ASensorChangeMidStreamReestimates)
{
  std::vector<Grid> frames = sequence("kinect", 3);
  for (Grid& g : sequence("kinect", 2, 4.0, 9))
    frames.push_back(g);
  for (Grid& g : sequence("stereo", 2, 1.0, 13))
    frames.push_back(g);
  const StreamRun run = runStream(frames, live());
  EXPECT_EQ(run.reused, (std::vector<bool>{false, true, true, false, true, false, true}));
  EXPECT_TRUE(sameBits(run.outputs[3], freshOutput(frames[3], live())));
  EXPECT_TRUE(sameBits(run.outputs[5], freshOutput(frames[5], live())));
}

// The ranges move (the scene seen from twice as far): the profile held beyond its edge bins would
// describe the new ranges badly, so the frame gets fresh estimates.
TEST(CarriedEstimates, RangesThatMovedAreReestimated)
{
  std::vector<Grid> frames = sequence("kinect", 2);
  Grid farther = frames[1];
  for (std::size_t i = 0; i < farther.size(); ++i)
    farther.x[i] *= 2.0f, farther.y[i] *= 2.0f, farther.z[i] *= 2.0f;
  frames.push_back(farther);
  const StreamRun run = runStream(frames, live());
  EXPECT_EQ(run.reused, (std::vector<bool>{false, true, false}));
  EXPECT_TRUE(sameBits(run.outputs[2], freshOutput(frames[2], live())));
}

// A frame of another size, a parameter the estimates depend on, or the age limit: fresh estimates.
TEST(CarriedEstimates, SizeParametersAndAgeRenewThem)
{
  const std::vector<Grid> frames = sequence("kinect", 2);
  FilterWorkspace workspace;
  const FilterParameters p = live();
  runFilter({&frames[0]}, 0, p, kOrigin, {}, workspace);
  FilterParameters other = p;
  other.search_window = 7;
  runFilter({&frames[1]}, 0, other, kOrigin, {}, workspace);
  EXPECT_FALSE(workspace.result().estimates_reused);
  runFilter({&frames[0]}, 0, other, kOrigin, {}, workspace);
  EXPECT_TRUE(workspace.result().estimates_reused);
  const std::vector<Grid> smaller = sequence("kinect", 1, 1.0, 3);
  Grid cut = smaller[0];
  cut.width = 80;
  cut.x.resize(80 * 120), cut.y.resize(80 * 120), cut.z.resize(80 * 120), cut.valid.resize(80 * 120);
  runFilter({&cut}, 0, other, kOrigin, {}, workspace);
  EXPECT_FALSE(workspace.result().estimates_reused);

  FilterWorkspace aged;
  int renewed = 0;
  for (int k = 0; k < 2 * tuned::kReuseMaxFrames; ++k) {
    runFilter({&frames[k % 2]}, 0, p, kOrigin, {}, aged);
    renewed += !aged.result().estimates_reused;
  }
  EXPECT_EQ(renewed, 2);
}

// Carried or not, the result does not depend on the thread count.
TEST(CarriedEstimates, OneTwoAndThreeThreadsGiveTheSameBits)
{
  std::vector<Grid> frames = sequence("stereo", 3);
  for (Grid& g : sequence("kinect", 2, 2.0, 17))
    frames.push_back(g);
  const StreamRun one = runStream(frames, live(1));
  for (int threads : {2, 3}) {
    const StreamRun more = runStream(frames, live(threads));
    EXPECT_EQ(more.reused, one.reused) << threads;
    for (std::size_t k = 0; k < frames.size(); ++k)
      EXPECT_TRUE(sameBits(more.outputs[k], one.outputs[k])) << threads << " threads, frame " << k;
  }
}

// A check of the same frame always agrees with itself; one of a frame with no valid point does not
// describe anything.
TEST(CarriedEstimates, TheCheckAgreesWithItsOwnFrame)
{
  const std::vector<Grid> frames = sequence("kinect", 1);
  std::vector<float> scratch[4];
  detail::CarriedEstimates carried;
  carried.valid = true;
  carried.parameters = live();
  carried.frames = 1;
  carried.signature = detail::estimateSignature(frames[0], kOrigin, scratch, 2);
  // Its four parts are taken side by side: one thread gives the same bits.
  const detail::EstimateSignature one = detail::estimateSignature(frames[0], kOrigin, scratch, 1);
  EXPECT_EQ(one.near.scale, carried.signature.near.scale);
  EXPECT_EQ(one.half.log_error, carried.signature.half.log_error);
  EXPECT_EQ(one.far.scale, carried.signature.far.scale);
  EXPECT_EQ(one.range_low, carried.signature.range_low);
  EXPECT_EQ(one.range_high, carried.signature.range_high);
  EXPECT_EQ(one.range_samples, carried.signature.range_samples);
  EXPECT_GT(carried.signature.near.samples, 1000u);
  EXPECT_GT(carried.signature.near.log_error, 0.0f);
  EXPECT_LT(carried.signature.near.log_error, 0.1f);
  EXPECT_GT(carried.signature.range_high, carried.signature.range_low);
  EXPECT_TRUE(detail::carriedEstimatesHold(carried, carried.signature, frames[0], live()));
  Grid empty = frames[0];
  std::fill(empty.valid.begin(), empty.valid.end(), 0);
  const detail::EstimateSignature none = detail::estimateSignature(empty, kOrigin, scratch, 2);
  EXPECT_EQ(none.near.scale, 0.0f);
  EXPECT_FALSE(detail::carriedEstimatesHold(carried, none, empty, live()));
}

/// live() with dilation k (0: automatic).
FilterParameters
liveDilated(int k, int threads = 2)
{
  FilterParameters p = live(threads);
  p.dilation = k;
  return p;
}

// Every noise profile of a stream's runs is carried: the current frame's in each of the 4 phases
// of dilation 2 as well as on the whole frame, so that after the first frame a static stream
// estimates none.
TEST(CarriedEstimates, EveryProfileOfAStaticStreamIsCarried)
{
  for (int k : {0, 2})
    for (const char* noise : {"kinect", "stereo"}) {
      const std::vector<Grid> frames = sequence(noise, 4);
      FilterWorkspace workspace;
      std::vector<int> estimated;
      for (const Grid& frame : frames) {
        runFilter({&frame}, 0, liveDilated(k), kOrigin, {}, workspace);
        estimated.push_back(workspace.result().profiles_estimated);
      }
      EXPECT_GE(estimated[0], k == 2 ? 5 : 1) << noise << ", dilation " << k;
      EXPECT_EQ(estimated, (std::vector<int>{estimated[0], 0, 0, 0})) << noise << ", dilation " << k;
      FilterParameters p = liveDilated(k);
      p.reuse_estimates = false;
      runFilter({&frames[1]}, 0, p, kOrigin, {}, workspace);
      EXPECT_EQ(workspace.result().profiles_estimated, estimated[0]) << noise << ", dilation " << k;
    }
}

// The other frame of a window (a recursive stream's history) keeps its profile while a check of it
// agrees with the frame the profile was made on: a fresh draw of the same sensor's noise there
// gets the carried profile (its bandwidths to the bit, where a fresh estimate differs); a frame
// four times as noisy gets a fresh profile, and so the bandwidths a fresh run gives it.
TEST(CarriedEstimates, AWindowsOtherFrameKeepsItsProfileUntilItChanges)
{
  for (const char* noise : {"kinect", "stereo"}) {
    const std::vector<Grid> current = sequence(noise, 3);
    const std::vector<Grid> other = sequence(noise, 2, 1.0, 23);
    const std::vector<Grid> noisier = sequence(noise, 1, 4.0, 25);
    const FilterParameters p = liveDilated(noise[0] == 's' ? 2 : 0);
    FilterWorkspace workspace;
    runFilter({&other[0], &current[0]}, 1, p, kOrigin, {}, workspace);

    runFilter({&other[1], &current[1]}, 1, p, kOrigin, {}, workspace);
    EXPECT_TRUE(workspace.result().estimates_reused) << noise;
    EXPECT_EQ(workspace.result().profiles_estimated, 0) << noise;
    // The bandwidths are the profile's at the current frame's median range.
    const FilterRun carried = runFilter({&other[0], &current[1]}, 1, p, kOrigin, {});
    EXPECT_EQ(workspace.result().bandwidths[0].similarity, carried.bandwidths[0].similarity) << noise;
    const FilterRun fresh = runFilter({&other[1], &current[1]}, 1, p, kOrigin, {});
    EXPECT_NE(fresh.bandwidths[0].similarity, carried.bandwidths[0].similarity) << noise;

    runFilter({&noisier[0], &current[2]}, 1, p, kOrigin, {}, workspace);
    EXPECT_GE(workspace.result().profiles_estimated, 1) << noise;
    const FilterRun renewed = runFilter({&noisier[0], &current[2]}, 1, p, kOrigin, {});
    EXPECT_EQ(workspace.result().bandwidths[0].similarity, renewed.bandwidths[0].similarity) << noise;
    EXPECT_EQ(workspace.result().bandwidths[0].distance, renewed.bandwidths[0].distance) << noise;
  }
}

// Windows of two frames, carried profiles and all: the same bits on 1, 2 and 3 threads.
TEST(CarriedEstimates, WindowsGiveTheSameBitsOnOneTwoAndThreeThreads)
{
  const std::vector<Grid> frames = sequence("stereo", 4, 1.0, 27);
  auto run = [&frames](int threads) {
    FilterWorkspace workspace;
    std::vector<Grid> outputs;
    for (std::size_t k = 1; k < frames.size(); ++k) {
      runFilter({&frames[k - 1], &frames[k]}, 1, liveDilated(2, threads), kOrigin, {}, workspace);
      outputs.push_back(workspace.result().output);
    }
    return outputs;
  };
  const std::vector<Grid> one = run(1);
  for (int threads : {2, 3}) {
    const std::vector<Grid> more = run(threads);
    for (std::size_t k = 0; k < one.size(); ++k)
      EXPECT_TRUE(sameBits(more[k], one[k])) << threads << " threads, window " << k;
  }
}
