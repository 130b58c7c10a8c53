// The process's heap for the buffers of filter runs (process_memory.h).
#include <range_nlm/io/process_memory.h>

#include <cstdint>
#include <cstdlib>

#if defined(__GLIBC__)
#include <malloc.h>
#include <sys/mman.h>
#endif

namespace range_nlm
{
namespace io
{

HeapSetup
preferHugePagesForBuffers()
{
  HeapSetup setup;
#if defined(__GLIBC__)
  constexpr std::size_t kMiB = std::size_t(1) << 20;
  // glibc takes at most 32 MB as the mmap threshold on 64-bit systems: the heap is grown in
  // blocks just below it.
  constexpr std::size_t kThreshold = 32 * kMiB, kBlock = 30 * kMiB, kBlocks = 6, kHugePage = 2 * kMiB;
  if (mallopt(M_MMAP_THRESHOLD, static_cast<int>(kThreshold)) == 0 ||
      mallopt(M_TRIM_THRESHOLD, static_cast<int>(1024 * kMiB)) == 0)
    return setup;
  setup.heap_below_bytes = kThreshold;
  // The blocks lie one after the other on the heap; freed, they join its top, from which the
  // frames' buffers are then cut. Only their untouched pages are marked, whole huge pages.
  void* blocks[kBlocks] = {};
  for (std::size_t b = 0; b < kBlocks; ++b) {
    blocks[b] = std::malloc(kBlock);
    if (!blocks[b])
      break;
    const std::uintptr_t at = reinterpret_cast<std::uintptr_t>(blocks[b]);
    const std::uintptr_t begin = (at + kHugePage - 1) / kHugePage * kHugePage;
    const std::uintptr_t end = (at + kBlock) / kHugePage * kHugePage;
    if (end > begin && ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE) == 0)
      setup.marked_bytes += end - begin;
  }
  for (void* block : blocks)
    std::free(block);
#endif
  return setup;
}

} // namespace io
} // namespace range_nlm
