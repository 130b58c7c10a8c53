// The process's heap for filter runs: buffers kept on a heap that asks for transparent huge pages.
#include <range_nlm/io/process_memory.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

using namespace range_nlm;

namespace
{

/// The kernel's transparent huge page mode ("always", "madvise" or "never"), empty without them.
std::string
hugePageMode()
{
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  std::getline(in, line);
  const std::size_t open = line.find('['), close = line.find(']');
  return open == std::string::npos || close == std::string::npos ? "" : line.substr(open + 1, close - open - 1);
}

/// The VmFlags of the mapping of this process that holds `address` (/proc/self/smaps), empty if
/// none does.
std::string
flagsOfMappingAt(const void* address)
{
  const std::uintptr_t at = reinterpret_cast<std::uintptr_t>(address);
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    std::uintptr_t begin = 0, end = 0;
    char dash = 0;
    std::istringstream range(line);
    if (range >> std::hex >> begin >> dash >> end && dash == '-' && line.find(':') > line.find(' ')) {
      inside = begin <= at && at < end;
      continue;
    }
    if (inside && line.rfind("VmFlags:", 0) == 0)
      return line.substr(8);
  }
  return "";
}

} // namespace

// After the call, a frame-sized buffer (three 640 x 480 planes of floats, far above glibc's
// default 128 KiB mmap threshold) is cut from the heap, not mapped on its own, and its pages lie in
// memory marked for transparent huge pages ("hg").
TEST(ProcessMemory, FrameSizedBuffersComeFromAHeapMarkedForHugePages)
{
#if !defined(__GLIBC__)
  GTEST_SKIP() << "the heap settings are glibc's";
#endif
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer's allocator takes the place of glibc's and ignores its settings";
#endif
  const io::HeapSetup setup = io::preferHugePagesForBuffers();
  EXPECT_EQ(setup.heap_below_bytes, std::size_t(32) << 20);
  const std::size_t bytes = std::size_t(640) * 480 * sizeof(float) * 3;
  void* buffer = std::malloc(bytes);
  ASSERT_NE(buffer, nullptr);
  // Its first whole huge page (the heap's part before the first 2 MiB boundary stays unmarked).
  const std::uintptr_t huge = std::uintptr_t(2) << 20;
  const std::uintptr_t page = (reinterpret_cast<std::uintptr_t>(buffer) + huge - 1) / huge * huge;
  const std::string flags = flagsOfMappingAt(reinterpret_cast<const void*>(page));
  std::free(buffer);
  ASSERT_FALSE(flags.empty()) << "no mapping holds the buffer";
  const std::string mode = hugePageMode();
  if (mode.empty() || mode == "never")
    GTEST_SKIP() << "transparent huge pages are off (" << (mode.empty() ? "absent" : mode) << ")";
  EXPECT_GT(setup.marked_bytes, std::size_t(100) << 20);
  EXPECT_NE(flags.find(" hg"), std::string::npos) << "VmFlags:" << flags;
}
