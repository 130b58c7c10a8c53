#include "cli/run_report.h"

#include "cli/cli.h"

#include <nlohmann/json.hpp>

#include <iomanip>
#include <iostream>

namespace range_nlm
{
namespace tools
{
namespace
{

/// The shard of a sharded run, for the summary.
nlohmann::json
shardJson(const ShardJob& sharding, std::size_t sequence_frames, bool recursive)
{
  const ShardPlan& plan = sharding.plan;
  nlohmann::json shard = {{"index", sharding.shard.index},
                          {"count", sharding.shard.count},
                          {"sequence_frames", sequence_frames},
                          {"first_frame", plan.writes.begin},
                          {"frames", plan.writes.size()},
                          {"first_frame_read", plan.reads.front().begin},
                          {"frames_read", plan.reads.front().size()}};
  if (recursive)
    shard["warmup"] = sharding.warmup == kWholeHistory ? nlohmann::json("all") : nlohmann::json(sharding.warmup);
  return shard;
}

} // namespace

void
printFrameLine(const FrameReport& report)
{
  if (report.unfiltered.empty())
    std::cout << printable(report.name) << ": " << std::fixed << std::setprecision(1) << report.milliseconds << " ms, d = "
              << std::setprecision(6) << report.bandwidths.distance << ", s = " << report.bandwidths.similarity
              << (report.outliers_moved > 0 ? ", " + std::to_string(report.outliers_moved) + " outliers moved"
                                            : std::string())
              << std::endl;
  else
    std::cout << printable(report.name) << ": not filtered, written unchanged (" << printable(report.unfiltered) << ")"
              << std::endl;
}

void
printSkippedLine(const std::string& name)
{
  std::cout << printable(name) << ": skipped (complete output exists)" << std::endl;
}

void
printSummaryJson(const Summary& s, const ShardJob& sharding, std::size_t sequence_frames, bool recursive)
{
  nlohmann::json out;
  double total = 0.0;
  std::size_t unfiltered = 0;
  nlohmann::json outputs = nlohmann::json::array();
  for (const FrameReport& r : s.written) {
    total += r.milliseconds;
    nlohmann::json o = {{"file", r.name},
                        {"ms", r.milliseconds},
                        {"distance_bandwidth", r.bandwidths.distance},
                        {"similarity_bandwidth", r.bandwidths.similarity},
                        {"outliers_moved", r.outliers_moved},
                        {"filtered", r.unfiltered.empty()}};
    if (!r.unfiltered.empty()) {
      o["reason"] = r.unfiltered;
      ++unfiltered;
    }
    outputs.push_back(o);
  }
  nlohmann::json unreadable = nlohmann::json::array();
  for (const auto& u : s.unreadable)
    unreadable.push_back({{"file", u.first}, {"error", u.second}});
  out["frames"] = s.written.size();
  out["skipped"] = s.skipped;
  out["unfiltered"] = unfiltered;
  out["unreadable"] = unreadable;
  out["width"] = s.width;
  out["height"] = s.height;
  out["filter_ms_total"] = total;
  out["frames_read"] = s.frames_read;
  out["frames_filtered"] = s.frames_filtered;
  out["filter_ms_all"] = s.filtered_ms;
  out["wall_ms"] = s.wall_ms;
  out["outputs"] = outputs;
  if (sharding.sharded)
    out["shard"] = shardJson(sharding, sequence_frames, recursive);
  // Non-finite numbers (an infinite bandwidth) become null; invalid UTF-8 in a file name is
  // replaced rather than ending the run.
  std::cout << out.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << std::endl;
}

int
reportEnd(const Summary& summary, bool quiet)
{
  std::size_t unfiltered = 0;
  for (const FrameReport& r : summary.written)
    unfiltered += !r.unfiltered.empty();
  if (!quiet && summary.written.size() + summary.skipped > 1 && unfiltered > 0)
    std::cout << unfiltered << " frame(s) could not be filtered and were written unchanged" << std::endl;
  if (!summary.unreadable.empty()) {
    std::cerr << "range_nlm_denoise: " << summary.unreadable.size() << " frame(s) could not be read and were skipped:\n";
    for (const auto& u : summary.unreadable)
      std::cerr << "  " << printable(u.second) << "\n"; // the message names the file
    std::cerr << std::flush;
    return 3;
  }
  return 0;
}

} // namespace tools
} // namespace range_nlm
