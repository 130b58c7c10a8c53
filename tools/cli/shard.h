// Cutting a recording into shards that separate machines filter independently (range_nlm_denoise
// --shard K/N): which frames a shard writes, and which frames every pass of its schedule has to
// read and produce for those outputs to be byte-identical to a run over the whole recording.
// Pure arithmetic, no file access.
#pragma once

#include <range_nlm/temporal_stream.h>

#include <cstddef>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{

/// Shard `index` (0-based) of `count`.
struct Shard
{
  std::size_t index = 0;
  std::size_t count = 1;
};

/// Reads an environment variable: null if it is not set.
using EnvironmentLookup = std::function<const char*(const char*)>;

/// Parses the value of --shard: "K/N" (0 <= K < N, N >= 1), or "slurm": K =
/// SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN (MIN taken as 0 if unset), N =
/// SLURM_ARRAY_TASK_COUNT; the array must be contiguous with step 1 (MAX - MIN + 1 == COUNT).
/// Throws UsageError naming the value (and the variable) that is wrong.
Shard
parseShard(const std::string& spec, const EnvironmentLookup& environment);

/// A half-open range of frame indices [begin, end).
struct FrameRange
{
  std::size_t begin = 0;
  std::size_t end = 0;
  std::size_t size() const { return end - begin; }
  bool empty() const { return end == begin; }
  bool contains(std::size_t t) const { return t >= begin && t < end; }
  bool operator==(const FrameRange& o) const { return begin == o.begin && end == o.end; }
};

/// The frames shard K of N writes, out of `frames`: contiguous, in order, the shards together
/// cover every frame once. Sizes differ by at most one, the first frames % N shards being the
/// longer ones; with more shards than frames the last shards are empty. Throws
/// std::invalid_argument for K >= N or N == 0.
FrameRange
shardFrames(std::size_t frames, const Shard& shard);

/// How one pass of a schedule reaches its neighbours (the radius and window of its TemporalStream).
struct PassReach
{
  int radius = 0;
  TemporalWindow window = TemporalWindow::centred;
};

/// Warm-up that means "the whole history": a recursive pass then reads every frame from the start.
constexpr std::size_t kWholeHistory = std::numeric_limits<std::size_t>::max();

/// Frames before and after a run of outputs that a schedule reads.
struct Halo
{
  std::size_t before = 0;
  std::size_t after = 0;
};

/// The halo of a schedule: the passes compose, each reading its radius around every frame the
/// next pass (or the output) needs, so the halo is the sum over the passes of
///   centred:   r before, r after;
///   causal:    r before, 0 after;
///   recursive: `warmup` before (the history that is replayed; 0 if r == 0), 0 after.
/// Saturates at kWholeHistory.
Halo
scheduleHalo(const std::vector<PassReach>& passes, std::size_t warmup);

/// What the passes of a schedule do for one shard, from the output back to the input.
struct ShardPlan
{
  /// Frames the shard writes.
  FrameRange writes;
  /// produced[i]: frames pass i must produce (produced.back() == writes).
  std::vector<FrameRange> produced;
  /// reads[i]: frames pass i reads, i.e. pushes into its stream (reads[i + 1] == produced[i]);
  /// reads.front() are the input frames the shard loads. A recursive pass starts its history at
  /// reads[i].begin: exact when that is frame 0, an approximation after a shorter warm-up.
  std::vector<FrameRange> reads;
};

/// The plan of shard K of N over `frames` for the schedule `passes`, with `warmup` frames of
/// history replayed before the shard by each recursive pass (kWholeHistory: from frame 0, exact).
/// All ranges are clipped to [0, frames). An empty shard reads nothing.
ShardPlan
planShard(std::size_t frames, const Shard& shard, const std::vector<PassReach>& passes, std::size_t warmup);

/// Frames a pass reads to produce the frames marked in `needed` (the exact, per-frame form of
/// the ranges above, for sets with gaps such as the unfinished frames of a resumed run).
/// A recursive pass reads every frame from `history_begin` to the last needed one.
std::vector<bool>
framesRead(const PassReach& pass, const std::vector<bool>& needed, std::size_t history_begin);

} // namespace tools
} // namespace range_nlm
