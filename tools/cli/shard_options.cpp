#include "cli/shard_options.h"

#include "cli/cli.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace po = boost::program_options;

namespace range_nlm
{
namespace tools
{
namespace
{

/// The largest radius of a recursive pass (0: none).
std::size_t
largestRecursiveRadius(const std::vector<PassReach>& passes)
{
  std::size_t radius = 0;
  for (const PassReach& pass : passes)
    if (pass.window == TemporalWindow::recursive && pass.radius > 0)
      radius = std::max(radius, static_cast<std::size_t>(pass.radius));
  return radius;
}

/// The value of --shard-warmup: a number of frames or 'all'.
std::size_t
parseWarmup(const std::string& text)
{
  if (text == "all")
    return kWholeHistory;
  try {
    std::size_t used = 0;
    const long long v = std::stoll(text, &used);
    if (used != text.size() || v < 0)
      throw std::invalid_argument(text);
    return static_cast<std::size_t>(v);
  } catch (const std::exception&) {
    throw UsageError("--shard-warmup must be a number of frames >= 0 or 'all', got '" + text + "'");
  }
}

} // namespace

bool
hasRecursivePass(const std::vector<PassReach>& passes)
{
  return std::any_of(passes.begin(), passes.end(), [](const PassReach& p) {
    return p.window == TemporalWindow::recursive && p.radius > 0;
  });
}

ShardJob
shardJobFrom(const po::variables_map& vm, const ShardContext& context)
{
  ShardJob job;
  job.sharded = vm.count("shard") > 0;
  const bool recursive = hasRecursivePass(context.passes);
  if (vm.count("shard-warmup")) {
    const std::string text = vm["shard-warmup"].as<std::string>();
    if (!job.sharded)
      throw UsageError("--shard-warmup " + text + " needs --shard");
    if (!recursive)
      throw UsageError("--shard-warmup " + text +
                       " applies to --recursive runs only (other schedules are cut exactly, without warm-up)");
    job.warmup = parseWarmup(text);
  } else if (job.sharded) {
    job.warmup = context.warmup_per_radius * largestRecursiveRadius(context.passes);
  }
  if (job.sharded) {
    if (context.single)
      throw UsageError("--shard cuts a directory of frames; give --input-dir and --output-dir");
    job.shard = parseShard(vm["shard"].as<std::string>(), [](const char* name) { return std::getenv(name); });
    std::error_code ec;
    if (std::filesystem::equivalent(vm["input-dir"].as<std::string>(), context.output_dir, ec))
      throw UsageError("--shard cannot write into the input directory: a shard would read frames another shard has "
                       "already filtered as its neighbours");
  }
  job.plan = planShard(context.frames, job.shard, context.passes, job.warmup);
  return job;
}

std::string
describeShard(const ShardJob& job, const std::vector<std::string>& inputs)
{
  const ShardPlan& plan = job.plan;
  std::ostringstream line;
  line << "shard " << job.shard.index << "/" << job.shard.count << ": ";
  if (plan.writes.empty()) {
    line << "no frames to write (" << inputs.size() << " frames, " << job.shard.count << " shards)";
    return line.str();
  }
  auto name = [&](std::size_t f) { return fileName(inputs[f]); };
  line << "frames " << plan.writes.begin << ".." << plan.writes.end - 1 << " of " << inputs.size() << " ("
       << name(plan.writes.begin) << " .. " << name(plan.writes.end - 1) << "), reading frames "
       << plan.reads.front().begin << ".." << plan.reads.front().end - 1;
  return line.str();
}

} // namespace tools
} // namespace range_nlm
