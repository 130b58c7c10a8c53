/// \file memory_budget.h
/// \brief A bound on the memory one frame may take, checked from a file's header before its body
/// is decompressed or any buffer of the frame's size is allocated (a 100 kB PNG can announce
/// 8000 x 6000 pixels, a PCD header 2^28 points).
#pragma once

#include <cstdint>
#include <functional>
#include <string>

namespace range_nlm
{
namespace io
{

struct MemoryBudget
{
  /// Largest number of bytes a frame may need; 0 = no limit (the default).
  std::uint64_t limit_bytes = 0;
  /// What the user changes to raise it, named in the message (e.g. "--memory-limit").
  std::string setting = "the memory limit";
  /// Bytes a frame of width x height points, each stored in `point_step` bytes, needs in the
  /// caller's processing (reading, filtering and writing it). Null: width * height * point_step.
  std::function<std::uint64_t(std::uint64_t width, std::uint64_t height, std::uint64_t point_step)> estimate;

  /// Bytes a width x height frame needs (saturating instead of overflowing).
  std::uint64_t need(std::uint64_t width, std::uint64_t height, std::uint64_t point_step) const
  {
    if (estimate)
      return estimate(width, height, point_step);
    const std::uint64_t points = width * height; // both < 2^32
    return point_step != 0 && points > UINT64_MAX / point_step ? UINT64_MAX : points * point_step;
  }
  /// Empty if a width x height frame fits the limit; else why not, with the figures, e.g.
  /// "a 20000 x 20000 frame needs about 66400 MB of memory, more than the limit of 4096 MB
  /// (raise it with --memory-limit)". Callers prefix the file name.
  std::string refusal(std::uint64_t width, std::uint64_t height, std::uint64_t point_step) const
  {
    if (limit_bytes == 0)
      return "";
    const std::uint64_t bytes = need(width, height, point_step);
    if (bytes <= limit_bytes)
      return "";
    const std::uint64_t mb = 1024 * 1024;
    return "a " + std::to_string(width) + " x " + std::to_string(height) + " frame needs about " +
           std::to_string((bytes + mb - 1) / mb) + " MB of memory, more than the limit of " +
           std::to_string(limit_bytes / mb) + " MB (raise it with " + setting + " if the machine has the memory)";
  }
};

} // namespace io
} // namespace range_nlm
