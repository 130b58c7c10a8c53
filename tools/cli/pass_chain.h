// A schedule of filter passes run over a sequence of frames: each pass a TemporalStream feeding
// the next, each filtering only the frames that the next one (or the output) reads.
#pragma once

#include "cli/shard.h"

#include <range_nlm/parameters.h>
#include <range_nlm/temporal_stream.h>

#include <pcl/point_types.h>

#include <cstddef>
#include <deque>
#include <memory>
#include <vector>

namespace range_nlm
{
namespace tools
{

/// One pass of a schedule as the chain runs it: the filter's parameters and how it reaches its
/// neighbours.
struct ChainPass
{
  FilterParameters parameters;
  PassReach reach;
};

/// What became of one input frame that came out of the chain.
struct ChainOutput
{
  pcl::PointCloud<pcl::PointXYZ>::ConstPtr cloud; // null: not wanted (--resume: finished before)
  TemporalStream<pcl::PointXYZ>::OutputInfo info; // of the first pass
};

/// The chain of passes, each a TemporalStream, feeding the next.
class PassChain
{
public:
  /// `wanted[t]`: the result of frame t is to be written. From the last pass back, each pass
  /// filters only the frames that the next one reads. A recursive pass at `level` starts its
  /// history at frame `history_begin[level]` (0: the whole history).
  PassChain(const std::vector<ChainPass>& passes, const std::vector<bool>& wanted,
            const std::vector<std::size_t>& history_begin, StageObserver* observer);
  /// False if no result depends on input frame t: it need not even be loaded.
  bool inputRead(std::size_t t) const { return inputs_read_[t]; }
  /// Pushes a frame through every pass; returns the finished frames in order.
  std::vector<ChainOutput> push(const pcl::PointCloud<pcl::PointXYZ>::ConstPtr& frame)
  {
    return feed(0, {{frame, {}}}, false);
  }
  std::vector<ChainOutput> flush() { return feed(0, {}, true); }
  /// Frames filtered so far, counted once per pass that filtered them (the halo of a shard and
  /// the history of a recursive pass included).
  std::size_t framesFiltered() const { return filtered_; }

private:
  /// One pass: its stream and which of its frames the next pass (or the output) reads.
  struct Level
  {
    std::unique_ptr<TemporalStream<pcl::PointXYZ>> stream;
    std::vector<bool> needed;
    std::size_t pushed = 0, emitted = 0;
    std::deque<TemporalStream<pcl::PointXYZ>::OutputInfo> carried;
  };

  std::vector<ChainOutput> feed(std::size_t level, const std::vector<ChainOutput>& in, bool flush);
  /// The frames that came out of the pass at `level`, appended to `out` with their records.
  void take(std::size_t level, const std::vector<TemporalStream<pcl::PointXYZ>::CloudPtr>& ready,
            std::vector<ChainOutput>& out);

  std::vector<Level> levels_;
  std::vector<bool> inputs_read_;
  std::size_t filtered_ = 0;
};

} // namespace tools
} // namespace range_nlm
