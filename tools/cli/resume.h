// --resume: which outputs of an interrupted run are complete already, so that a run after it
// writes only the rest.
#pragma once

#include "cli/shard.h"

#include <range_nlm/io/depth_image.h>
#include <range_nlm/io/pcd_file.h>

#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{

/// `path` holds a complete output of a width x height frame: a depth PNG (`png`) or a PCD file
/// of that size that can be read. False for a missing, truncated or unreadable file.
bool
isFinishedOutput(const std::string& path, bool png, const DepthIntrinsics& intrinsics, unsigned width,
                 unsigned height);

/// The size of the frames of a sequence (0 x 0: not known yet).
struct FrameSize
{
  unsigned width = 0;
  unsigned height = 0;
};

/// finished[f - writes.begin]: output f of `writes` is complete already. Outputs are checked
/// against the size of the first frame of `writes` that can be loaded (a frame that cannot is
/// left for its turn to report; its output and those before it count as unfinished), which is
/// returned in `size`.
std::vector<bool>
finishedOutputs(const std::vector<std::string>& inputs, const std::vector<std::string>& outputs,
                const FrameRange& writes, bool png, const DepthIntrinsics& intrinsics, const io::MemoryBudget& budget,
                FrameSize& size);

} // namespace tools
} // namespace range_nlm
