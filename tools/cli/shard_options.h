// The command line of a sharded run (range_nlm_denoise --shard K/N [--shard-warmup W]): the
// shard, the history a recursive pass replays before it, and the plan of the frames it writes
// and reads (shard.h), with the line that tells what a shard does.
#pragma once

#include "cli/shard.h"

#include <boost/program_options/variables_map.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{

/// What --shard and --shard-warmup ask of a run (without --shard: every frame, shard 0 of 1).
struct ShardJob
{
  bool sharded = false;
  Shard shard;
  /// Frames of history each recursive pass replays before the shard (kWholeHistory: all).
  std::size_t warmup = kWholeHistory;
  /// The frames written and read.
  ShardPlan plan;
};

/// The inputs of shardJobFrom besides the command line.
struct ShardContext
{
  /// The passes of the schedule, in order.
  std::vector<PassReach> passes;
  /// A single-frame run (INPUT OUTPUT): --shard is refused.
  bool single = false;
  /// Frames in the input, in name order.
  std::size_t frames = 0;
  std::string output_dir;
  /// --recursive without --shard-warmup: frames of history per frame of the largest recursive radius.
  std::size_t warmup_per_radius = 0;
};

/// --shard and --shard-warmup, checked (UsageError naming the option), and the plan of the shard.
/// A recursive pass is one of TemporalWindow::recursive with a radius above 0.
ShardJob
shardJobFrom(const boost::program_options::variables_map& vm, const ShardContext& context);

/// "shard K/N: frames A..B of T (a .. b), reading frames C..D", or that the shard writes nothing:
/// the first line of a sharded run. `inputs` are the input frames in name order.
std::string
describeShard(const ShardJob& job, const std::vector<std::string>& inputs);

/// True if a pass of `passes` is recursive (with a radius above 0): --shard-warmup applies.
bool
hasRecursivePass(const std::vector<PassReach>& passes);

} // namespace tools
} // namespace range_nlm
