// Shard arithmetic of range_nlm_denoise --shard (tools/cli/shard.h): which frames a shard writes,
// the halo a schedule of passes needs around them, and --shard values that are refused.
#include "cli/cli.h"
#include "cli/shard.h"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <string>
#include <vector>

using namespace range_nlm;
using namespace range_nlm::tools;

namespace
{

/// An environment of the given variables only.
EnvironmentLookup
environment(const std::map<std::string, std::string>& variables)
{
  return [variables](const char* name) -> const char* {
    const auto it = variables.find(name);
    return it == variables.end() ? nullptr : it->second.c_str();
  };
}

const EnvironmentLookup kNoEnvironment = environment({});

/// The message of the UsageError that parseShard throws ("" if it does not throw).
std::string
refusal(const std::string& spec, const EnvironmentLookup& env = kNoEnvironment)
{
  try {
    parseShard(spec, env);
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

} // namespace

TEST(ShardFrames, ContiguousShardsCoverEveryFrameOnceWithSizesDifferingByAtMostOne)
{
  for (std::size_t frames : {0u, 1u, 2u, 7u, 10u, 23u, 100u})
    for (std::size_t count : {1u, 2u, 3u, 4u, 7u, 10u, 31u}) {
      std::size_t next = 0, smallest = frames, largest = 0;
      for (std::size_t k = 0; k < count; ++k) {
        const FrameRange r = shardFrames(frames, {k, count});
        EXPECT_EQ(r.begin, next) << frames << " frames, shard " << k << "/" << count;
        EXPECT_LE(r.begin, r.end);
        next = r.end;
        smallest = std::min(smallest, r.size());
        largest = std::max(largest, r.size());
      }
      EXPECT_EQ(next, frames) << frames << " frames, " << count << " shards";
      EXPECT_LE(largest - smallest, 1u) << frames << " frames, " << count << " shards";
    }
}

TEST(ShardFrames, FirstAndLastShard)
{
  // 10 frames in 4 shards: 3, 3, 2, 2.
  EXPECT_EQ(shardFrames(10, {0, 4}), (FrameRange{0, 3}));
  EXPECT_EQ(shardFrames(10, {1, 4}), (FrameRange{3, 6}));
  EXPECT_EQ(shardFrames(10, {2, 4}), (FrameRange{6, 8}));
  EXPECT_EQ(shardFrames(10, {3, 4}), (FrameRange{8, 10}));
  EXPECT_EQ(shardFrames(10, {0, 1}), (FrameRange{0, 10}));
}

TEST(ShardFrames, MoreShardsThanFramesLeavesTheLastShardsEmpty)
{
  EXPECT_EQ(shardFrames(3, {0, 5}), (FrameRange{0, 1}));
  EXPECT_EQ(shardFrames(3, {2, 5}), (FrameRange{2, 3}));
  EXPECT_TRUE(shardFrames(3, {3, 5}).empty());
  EXPECT_TRUE(shardFrames(3, {4, 5}).empty());
  EXPECT_TRUE(shardFrames(0, {0, 1}).empty());
}

TEST(ShardFrames, ShardsThatDoNotExistAreRefused)
{
  EXPECT_THROW(shardFrames(10, {4, 4}), std::invalid_argument);
  EXPECT_THROW(shardFrames(10, {0, 0}), std::invalid_argument);
}

TEST(ParseShard, KOfN)
{
  const Shard s = parseShard("2/5", kNoEnvironment);
  EXPECT_EQ(s.index, 2u);
  EXPECT_EQ(s.count, 5u);
  EXPECT_EQ(parseShard("0/1", kNoEnvironment).count, 1u);
}

TEST(ParseShard, BadValuesAreRefusedWithAMessageNamingThem)
{
  EXPECT_NE(refusal("4/4").find("'4/4'"), std::string::npos) << refusal("4/4");
  EXPECT_NE(refusal("4/4").find("K must be less than N"), std::string::npos);
  EXPECT_NE(refusal("0/0").find("'0/0'"), std::string::npos);
  EXPECT_NE(refusal("0/0").find("at least 1"), std::string::npos);
  for (const std::string bad : {"", "3", "/4", "1/", "-1/4", "1/-4", "a/b", "1/4x", " 1/4", "1.0/4", "1/4/2", "+1/4",
                                "99999999999999999999/1"}) {
    const std::string message = refusal(bad);
    EXPECT_NE(message.find("'" + bad + "'"), std::string::npos) << bad << ": " << message;
    EXPECT_NE(message.find("expected K/N"), std::string::npos) << bad << ": " << message;
  }
}

TEST(ParseShard, SlurmTakesTheTaskOfTheArray)
{
  const Shard s = parseShard("slurm", environment({{"SLURM_ARRAY_TASK_ID", "7"},
                                                   {"SLURM_ARRAY_TASK_MIN", "5"},
                                                   {"SLURM_ARRAY_TASK_MAX", "8"},
                                                   {"SLURM_ARRAY_TASK_COUNT", "4"},
                                                   {"SLURM_ARRAY_TASK_STEP", "1"}}));
  EXPECT_EQ(s.index, 2u);
  EXPECT_EQ(s.count, 4u);
  // Without SLURM_ARRAY_TASK_MIN the array starts at 0.
  const Shard t = parseShard("slurm", environment({{"SLURM_ARRAY_TASK_ID", "1"}, {"SLURM_ARRAY_TASK_COUNT", "3"}}));
  EXPECT_EQ(t.index, 1u);
  EXPECT_EQ(t.count, 3u);
}

TEST(ParseShard, SlurmOutsideAContiguousArrayIsRefused)
{
  std::string m = refusal("slurm");
  EXPECT_NE(m.find("SLURM_ARRAY_TASK_ID is not set"), std::string::npos) << m;
  m = refusal("slurm", environment({{"SLURM_ARRAY_TASK_ID", "1"}}));
  EXPECT_NE(m.find("SLURM_ARRAY_TASK_COUNT is not set"), std::string::npos) << m;
  m = refusal("slurm", environment({{"SLURM_ARRAY_TASK_ID", "x1"}, {"SLURM_ARRAY_TASK_COUNT", "3"}}));
  EXPECT_NE(m.find("SLURM_ARRAY_TASK_ID is 'x1'"), std::string::npos) << m;
  // --array=3-7:2: tasks 3, 5, 7.
  m = refusal("slurm", environment({{"SLURM_ARRAY_TASK_ID", "5"},
                                    {"SLURM_ARRAY_TASK_MIN", "3"},
                                    {"SLURM_ARRAY_TASK_MAX", "7"},
                                    {"SLURM_ARRAY_TASK_COUNT", "3"},
                                    {"SLURM_ARRAY_TASK_STEP", "2"}}));
  EXPECT_NE(m.find("not contiguous"), std::string::npos) << m;
  EXPECT_NE(m.find("STEP 2"), std::string::npos) << m;
  // --array=1,4,5.
  m = refusal("slurm", environment({{"SLURM_ARRAY_TASK_ID", "4"},
                                    {"SLURM_ARRAY_TASK_MIN", "1"},
                                    {"SLURM_ARRAY_TASK_MAX", "5"},
                                    {"SLURM_ARRAY_TASK_COUNT", "3"}}));
  EXPECT_NE(m.find("not contiguous"), std::string::npos) << m;
  m = refusal("slurm", environment({{"SLURM_ARRAY_TASK_ID", "9"}, {"SLURM_ARRAY_TASK_COUNT", "3"}}));
  EXPECT_NE(m.find("SLURM_ARRAY_TASK_ID 9 is outside the array 0-2"), std::string::npos) << m;
}

TEST(ScheduleHalo, PassesAddTheirRadii)
{
  using W = TemporalWindow;
  Halo h = scheduleHalo({{2, W::centred}, {1, W::centred}}, kWholeHistory);
  EXPECT_EQ(h.before, 3u);
  EXPECT_EQ(h.after, 3u);
  h = scheduleHalo({{2, W::causal}, {3, W::centred}, {0, W::centred}}, kWholeHistory);
  EXPECT_EQ(h.before, 5u);
  EXPECT_EQ(h.after, 3u);
  h = scheduleHalo({{2, W::recursive}, {1, W::centred}}, 16);
  EXPECT_EQ(h.before, 17u);
  EXPECT_EQ(h.after, 1u);
  h = scheduleHalo({{0, W::recursive}}, 16); // radius 0: no history to replay
  EXPECT_EQ(h.before, 0u);
  h = scheduleHalo({{1, W::recursive}, {1, W::recursive}}, kWholeHistory);
  EXPECT_EQ(h.before, kWholeHistory);
}

TEST(PlanShard, ReadsTheHaloClippedAtTheEnds)
{
  using W = TemporalWindow;
  const std::vector<PassReach> two_pass{{2, W::centred}, {1, W::centred}};
  // 20 frames in 4 shards of 5; the halo is 3 on each side.
  ShardPlan p = planShard(20, {1, 4}, two_pass, kWholeHistory);
  EXPECT_EQ(p.writes, (FrameRange{5, 10}));
  EXPECT_EQ(p.produced[1], (FrameRange{5, 10}));
  EXPECT_EQ(p.reads[1], (FrameRange{4, 11}));
  EXPECT_EQ(p.produced[0], (FrameRange{4, 11}));
  EXPECT_EQ(p.reads[0], (FrameRange{2, 13}));
  p = planShard(20, {0, 4}, two_pass, kWholeHistory); // first shard: nothing before frame 0
  EXPECT_EQ(p.reads[0], (FrameRange{0, 8}));
  p = planShard(20, {3, 4}, two_pass, kWholeHistory); // last shard: nothing after frame 19
  EXPECT_EQ(p.reads[0], (FrameRange{12, 20}));
}

TEST(PlanShard, RadiusLargerThanAShardReachesIntoSeveralShards)
{
  // 12 frames in 6 shards of 2, radius 5: shard 2 (frames 4, 5) reads 0 .. 10.
  const ShardPlan p = planShard(12, {2, 6}, {{5, TemporalWindow::centred}}, kWholeHistory);
  EXPECT_EQ(p.writes, (FrameRange{4, 6}));
  EXPECT_EQ(p.reads[0], (FrameRange{0, 11}));
  const ShardPlan causal = planShard(12, {5, 6}, {{5, TemporalWindow::causal}}, kWholeHistory);
  EXPECT_EQ(causal.reads[0], (FrameRange{5, 12}));
}

TEST(PlanShard, EmptyShardReadsNothing)
{
  const ShardPlan p = planShard(3, {4, 5}, {{2, TemporalWindow::centred}, {1, TemporalWindow::centred}}, kWholeHistory);
  EXPECT_TRUE(p.writes.empty());
  EXPECT_TRUE(p.reads[0].empty());
  EXPECT_TRUE(p.reads[1].empty());
}

TEST(PlanShard, RecursivePassesReplayTheWarmUpOrTheWholeHistory)
{
  using W = TemporalWindow;
  ShardPlan p = planShard(100, {2, 4}, {{2, W::recursive}}, 16);
  EXPECT_EQ(p.writes, (FrameRange{50, 75}));
  EXPECT_EQ(p.reads[0], (FrameRange{34, 75}));
  p = planShard(100, {2, 4}, {{2, W::recursive}}, kWholeHistory);
  EXPECT_EQ(p.reads[0], (FrameRange{0, 75}));
  // A centred pass after a recursive one: the recursive pass produces the centred pass's halo.
  p = planShard(100, {2, 4}, {{2, W::recursive}, {1, W::centred}}, 16);
  EXPECT_EQ(p.reads[1], (FrameRange{49, 76}));
  EXPECT_EQ(p.reads[0], (FrameRange{33, 76}));
}

// The ranges of planShard are exactly what the per-frame framesRead reads for a whole shard,
// composed from the last pass back: no frame more (wasted work) and none less (a different result).
TEST(PlanShard, AgreesWithThePerFrameComposition)
{
  std::mt19937 rng(7);
  const TemporalWindow windows[] = {TemporalWindow::centred, TemporalWindow::causal, TemporalWindow::recursive};
  for (int trial = 0; trial < 400; ++trial) {
    const std::size_t frames = rng() % 40;
    const std::size_t count = 1 + rng() % 9;
    const std::size_t warmup = trial % 5 == 0 ? kWholeHistory : rng() % 12;
    std::vector<PassReach> passes(1 + rng() % 3);
    for (PassReach& pass : passes)
      pass = {static_cast<int>(rng() % 6), windows[rng() % 3]};
    for (std::size_t k = 0; k < count; ++k) {
      const ShardPlan plan = planShard(frames, {k, count}, passes, warmup);
      std::vector<bool> needed(frames, false);
      for (std::size_t t = plan.writes.begin; t < plan.writes.end; ++t)
        needed[t] = true;
      for (std::size_t level = passes.size(); level-- > 0;) {
        needed = framesRead(passes[level], needed, plan.reads[level].begin);
        for (std::size_t t = 0; t < frames; ++t)
          ASSERT_EQ(needed[t], plan.reads[level].contains(t))
              << "trial " << trial << ", shard " << k << "/" << count << ", pass " << level << ", frame " << t;
      }
    }
  }
}

TEST(FramesRead, GapsOfAResumedRunAreKept)
{
  const std::vector<bool> needed{false, false, true, false, false, false, false, true, false, false};
  const std::vector<bool> centred = framesRead({1, TemporalWindow::centred}, needed, 0);
  EXPECT_EQ(centred, (std::vector<bool>{false, true, true, true, false, false, true, true, true, false}));
  const std::vector<bool> causal = framesRead({1, TemporalWindow::causal}, needed, 0);
  EXPECT_EQ(causal, (std::vector<bool>{false, true, true, false, false, false, true, true, false, false}));
  // A recursive pass reads every frame from the start of its history to the last one needed.
  const std::vector<bool> recursive = framesRead({1, TemporalWindow::recursive}, needed, 1);
  EXPECT_EQ(recursive, (std::vector<bool>{false, true, true, true, true, true, true, true, false, false}));
  EXPECT_EQ(framesRead({1, TemporalWindow::recursive}, std::vector<bool>(5, false), 0), std::vector<bool>(5, false));
}
