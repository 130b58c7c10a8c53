#include "cli/shard.h"

#include "cli/cli.h"

#include <algorithm>
#include <cctype>
#include <stdexcept>

namespace range_nlm
{
namespace tools
{

namespace
{

/// A non-negative decimal integer, or false (no sign, no spaces, no overflow).
bool
parseCount(const std::string& text, std::size_t& value)
{
  if (text.empty() || text.size() > 18 ||
      !std::all_of(text.begin(), text.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); }))
    return false;
  value = std::stoull(text);
  return true;
}

/// The value of a Slurm array variable as a count; throws UsageError naming it.
std::size_t
slurmVariable(const EnvironmentLookup& environment, const char* name, bool required, std::size_t fallback)
{
  const char* value = environment(name);
  if (!value) {
    if (!required)
      return fallback;
    throw UsageError(std::string("--shard slurm: ") + name +
                     " is not set (run it as a task of a Slurm job array, sbatch --array=0-N, or give --shard K/N)");
  }
  std::size_t n = 0;
  if (!parseCount(value, n))
    throw UsageError(std::string("--shard slurm: ") + name + " is '" + value + "', not a non-negative integer");
  return n;
}

std::size_t
saturatingAdd(std::size_t a, std::size_t b)
{
  return a > kWholeHistory - b ? kWholeHistory : a + b;
}

} // namespace

Shard
parseShard(const std::string& spec, const EnvironmentLookup& environment)
{
  Shard shard;
  if (spec == "slurm") {
    const std::size_t id = slurmVariable(environment, "SLURM_ARRAY_TASK_ID", true, 0);
    const std::size_t min = slurmVariable(environment, "SLURM_ARRAY_TASK_MIN", false, 0);
    shard.count = slurmVariable(environment, "SLURM_ARRAY_TASK_COUNT", true, 0);
    const std::size_t step = slurmVariable(environment, "SLURM_ARRAY_TASK_STEP", false, 1);
    const std::size_t max = slurmVariable(environment, "SLURM_ARRAY_TASK_MAX", false, min + shard.count - 1);
    if (shard.count == 0)
      throw UsageError("--shard slurm: SLURM_ARRAY_TASK_COUNT is 0");
    if (step != 1 || max < min || max - min + 1 != shard.count)
      throw UsageError("--shard slurm: the job array is not contiguous (SLURM_ARRAY_TASK_MIN " + std::to_string(min) +
                       ", MAX " + std::to_string(max) + ", STEP " + std::to_string(step) + ", COUNT " +
                       std::to_string(shard.count) + "); submit it as --array=0-" + std::to_string(shard.count - 1) +
                       " or give --shard K/N");
    if (id < min || id > max)
      throw UsageError("--shard slurm: SLURM_ARRAY_TASK_ID " + std::to_string(id) + " is outside the array " +
                       std::to_string(min) + "-" + std::to_string(max));
    shard.index = id - min;
    return shard;
  }
  const auto slash = spec.find('/');
  if (slash == std::string::npos || !parseCount(spec.substr(0, slash), shard.index) ||
      !parseCount(spec.substr(slash + 1), shard.count))
    throw UsageError("--shard '" + spec + "': expected K/N (shard K of N, counted from 0, e.g. 0/4) or 'slurm'");
  if (shard.count == 0)
    throw UsageError("--shard '" + spec + "': the number of shards N must be at least 1");
  if (shard.index >= shard.count)
    throw UsageError("--shard '" + spec + "': K must be less than N (shards are counted from 0: 0/" +
                     std::to_string(shard.count) + " .. " + std::to_string(shard.count - 1) + "/" +
                     std::to_string(shard.count) + ")");
  return shard;
}

FrameRange
shardFrames(std::size_t frames, const Shard& shard)
{
  if (shard.count == 0 || shard.index >= shard.count)
    throw std::invalid_argument("shard " + std::to_string(shard.index) + " of " + std::to_string(shard.count) +
                                " does not exist");
  const std::size_t base = frames / shard.count, longer = frames % shard.count;
  auto start = [&](std::size_t k) { return k * base + std::min(k, longer); };
  return {start(shard.index), start(shard.index + 1)};
}

Halo
scheduleHalo(const std::vector<PassReach>& passes, std::size_t warmup)
{
  Halo halo;
  for (const PassReach& pass : passes) {
    const std::size_t r = static_cast<std::size_t>(std::max(pass.radius, 0));
    if (r == 0)
      continue;
    switch (pass.window) {
    case TemporalWindow::centred:
      halo.before = saturatingAdd(halo.before, r);
      halo.after = saturatingAdd(halo.after, r);
      break;
    case TemporalWindow::causal:
      halo.before = saturatingAdd(halo.before, r);
      break;
    case TemporalWindow::recursive:
      halo.before = saturatingAdd(halo.before, warmup);
      break;
    }
  }
  return halo;
}

ShardPlan
planShard(std::size_t frames, const Shard& shard, const std::vector<PassReach>& passes, std::size_t warmup)
{
  ShardPlan plan;
  plan.writes = shardFrames(frames, shard);
  plan.produced.resize(passes.size());
  plan.reads.resize(passes.size());
  FrameRange next = plan.writes;
  for (std::size_t level = passes.size(); level-- > 0;) {
    plan.produced[level] = next;
    if (!next.empty()) {
      const Halo halo = scheduleHalo({passes[level]}, warmup);
      next.begin = next.begin > halo.before ? next.begin - halo.before : 0;
      next.end = std::min(saturatingAdd(next.end, halo.after), frames);
    }
    plan.reads[level] = next;
  }
  return plan;
}

std::vector<bool>
framesRead(const PassReach& pass, const std::vector<bool>& needed, std::size_t history_begin)
{
  std::vector<bool> read(needed.size(), false);
  const auto first = std::find(needed.begin(), needed.end(), true);
  if (first == needed.end())
    return read;
  const std::size_t r = static_cast<std::size_t>(std::max(pass.radius, 0));
  if (pass.window == TemporalWindow::recursive && r > 0) { // every output carries the history before it
    const std::size_t last = static_cast<std::size_t>(needed.rend() - std::find(needed.rbegin(), needed.rend(), true));
    const std::size_t begin = std::min(history_begin, static_cast<std::size_t>(first - needed.begin()));
    std::fill(read.begin() + begin, read.begin() + last, true);
    return read;
  }
  const bool causal = pass.window != TemporalWindow::centred;
  for (std::size_t t = 0; t < needed.size(); ++t)
    if (needed[t])
      for (std::size_t k = t >= r ? t - r : 0; k <= (causal ? t : std::min(t + r, needed.size() - 1)); ++k)
        read[k] = true;
  return read;
}

} // namespace tools
} // namespace range_nlm
