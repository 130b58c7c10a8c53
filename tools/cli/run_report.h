// What a run of range_nlm_denoise over frames tells: a line per frame, a JSON summary, and at the
// end the frames that could not be filtered or read, with the exit status that follows.
#pragma once

#include "cli/shard_options.h"

#include <range_nlm/core/pipeline.h>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace range_nlm
{
namespace tools
{

/// One frame written.
struct FrameReport
{
  std::string name;
  double milliseconds = 0.0;
  Bandwidths bandwidths;
  /// Why it was written unchanged (empty: filtered).
  std::string unfiltered;
  /// Isolated outliers moved onto their neighbours' surface (all passes).
  std::size_t outliers_moved = 0;
};

/// What a run did, for the summary and the exit status.
struct Summary
{
  std::vector<FrameReport> written;
  std::size_t skipped = 0; // --resume: complete output existed
  std::vector<std::pair<std::string, std::string>> unreadable; // file, error
  /// Frames loaded, and frames filtered, once per pass that filtered them, with their filter time:
  /// with the halo of a shard and the history of a recursive pass, the run's real cost.
  std::size_t frames_read = 0, frames_filtered = 0;
  double filtered_ms = 0.0;
  unsigned width = 0, height = 0;
  double wall_ms = 0.0;
};

/// "NAME: T ms, d = D, s = S[, N outliers moved]", or that the frame was written unchanged, on stdout.
void
printFrameLine(const FrameReport& report);

/// "NAME: skipped (complete output exists)" on stdout (--resume).
void
printSkippedLine(const std::string& name);

/// The summary as one line of JSON on stdout; with `sharding.sharded` its shard, out of
/// `sequence_frames`, and with `recursive` passes the warm-up.
void
printSummaryJson(const Summary& summary, const ShardJob& sharding, std::size_t sequence_frames, bool recursive);

/// The end of a run: unless `quiet`, how many frames of several were written unchanged (stdout);
/// the frames that could not be read (stderr). Returns the exit status: 3 if some could not be
/// read, else 0.
int
reportEnd(const Summary& summary, bool quiet);

} // namespace tools
} // namespace range_nlm
