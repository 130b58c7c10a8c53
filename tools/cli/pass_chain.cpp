#include "cli/pass_chain.h"

namespace range_nlm
{
namespace tools
{

PassChain::PassChain(const std::vector<ChainPass>& passes, const std::vector<bool>& wanted,
                     const std::vector<std::size_t>& history_begin, StageObserver* observer)
{
  std::vector<std::vector<bool>> needed(passes.size());
  std::vector<bool> next = wanted;
  for (std::size_t level = passes.size(); level-- > 0;) {
    needed[level] = next;
    next = framesRead(passes[level].reach, next, history_begin[level]);
  }
  inputs_read_ = next;
  for (std::size_t level = 0; level < passes.size(); ++level) {
    const ChainPass& pass = passes[level];
    levels_.push_back({std::make_unique<TemporalStream<pcl::PointXYZ>>(pass.reach.radius, pass.reach.window,
                                                                        pass.parameters),
                       needed[level], 0, 0, {}});
    levels_.back().stream->setStageObserver(observer);
  }
}

void
PassChain::take(std::size_t level, const std::vector<TemporalStream<pcl::PointXYZ>::CloudPtr>& ready,
                std::vector<ChainOutput>& out)
{
  Level& l = levels_[level];
  for (std::size_t i = 0; i < ready.size(); ++i) {
    // A recursive pass filters frames nothing needs too (its history); passed on as null, the
    // next recursive pass starts its own history exactly where the plan says.
    ChainOutput o{l.needed[l.emitted++] ? ready[i] : nullptr, l.stream->lastOutputs()[i]};
    // A frame passed over took no time; one that could not be filtered is written unchanged.
    filtered_ += o.info.milliseconds > 0.0 && o.info.problem.empty();
    const TemporalStream<pcl::PointXYZ>::OutputInfo before = l.carried.front();
    l.carried.pop_front();
    if (level > 0) {
      o.info.milliseconds += before.milliseconds;
      o.info.outliers_moved += before.outliers_moved;
      // A point an earlier pass filled stays marked: a later pass takes it for a measured one.
      if (o.info.filled.empty())
        o.info.filled = before.filled;
      else
        for (std::size_t k = 0; k < before.filled.size() && k < o.info.filled.size(); ++k)
          o.info.filled[k] |= before.filled[k];
      o.info.bandwidths = before.bandwidths;
      if (!before.problem.empty())
        o.info.problem = before.problem;
    }
    out.push_back(o);
  }
}

std::vector<ChainOutput>
PassChain::feed(std::size_t level, const std::vector<ChainOutput>& in, bool flush)
{
  Level& l = levels_[level];
  std::vector<ChainOutput> out;
  // Frames come out of every pass in order: the k-th output is the k-th input, whose record
  // from the earlier passes is carried along (first problem, first pass's bandwidths, time).
  for (const ChainOutput& f : in) {
    l.carried.push_back(f.info);
    take(level, l.stream->push(f.cloud, l.needed[l.pushed++]), out);
  }
  if (flush)
    take(level, l.stream->flush(), out);
  if (level + 1 == levels_.size())
    return out;
  return feed(level + 1, out, flush);
}

} // namespace tools
} // namespace range_nlm
