#include "cli/resume.h"

#include "cli/cli.h"

#include <exception>
#include <filesystem>

namespace range_nlm
{
namespace tools
{

bool
isFinishedOutput(const std::string& path, bool png, const DepthIntrinsics& intrinsics, unsigned width,
                 unsigned height)
{
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    return false;
  try {
    if (png) {
      const pcl::PointCloud<pcl::PointXYZ> cloud = loadDepthPng(path, intrinsics);
      return cloud.width == width && cloud.height == height;
    }
    const LoadedCloud loaded = loadCloud(path);
    return loaded.blob.width == width && loaded.blob.height == height;
  } catch (const std::exception&) {
    return false;
  }
}

std::vector<bool>
finishedOutputs(const std::vector<std::string>& inputs, const std::vector<std::string>& outputs,
                const FrameRange& writes, bool png, const DepthIntrinsics& intrinsics, const io::MemoryBudget& budget,
                FrameSize& size)
{
  std::vector<bool> finished(writes.size(), false);
  for (std::size_t f = writes.begin; f < writes.end; ++f) {
    if (size.width == 0) {
      try {
        const LoadedCloud first = loadFrame(inputs[f], intrinsics, budget);
        size.width = first.blob.width;
        size.height = first.blob.height;
      } catch (const InputError&) {
        continue; // reported when the frame's turn comes
      }
    }
    finished[f - writes.begin] = isFinishedOutput(outputs[f], png, intrinsics, size.width, size.height);
  }
  return finished;
}

} // namespace tools
} // namespace range_nlm
