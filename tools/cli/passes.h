// The passes of a range_nlm_denoise schedule (--pass): each a filter run with its own parameters
// and temporal window over the output of the one before.
#pragma once

#include "cli/shard.h"

#include <range_nlm/parameters.h>
#include <range_nlm/temporal_stream.h>

#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{

/// One filter pass of a schedule: parameters and temporal radius.
struct Pass
{
  FilterParameters parameters;
  int radius = 0;
  bool causal = false;
  /// The neighbour is the history of the frames before (TemporalWindow::recursive).
  bool recursive = false;

  TemporalWindow window() const
  {
    return recursive ? TemporalWindow::recursive : causal ? TemporalWindow::causal : TemporalWindow::centred;
  }
  PassReach reach() const { return {radius, window()}; }
};

/// The reach of each pass, for planning shards.
std::vector<PassReach>
reachOf(const std::vector<Pass>& passes);

/// A pass from a --pass value "key=value,key=value,...": `base` with each item applied. The keys
/// are `radius` and the pass keys of the parameter registry (search, patch, iterations, normal,
/// dilation, outlier_sigmas, ...; parameter_registry.h), each value of its field's type. Throws
/// UsageError naming the spec and the item or the parameter.
Pass
parsePass(const std::string& spec, const Pass& base);

/// "radius, search, patch, ...": the keys parsePass accepts.
std::string
passKeys();

} // namespace tools
} // namespace range_nlm
