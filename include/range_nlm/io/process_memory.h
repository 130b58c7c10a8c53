/// \file process_memory.h
/// \brief How a process that filters frames keeps its buffers: on a heap that is not given back
/// between frames and that asks the kernel for transparent huge pages. Process-wide, so the
/// library never does it by itself; range_nlm's tools and its ROS node call it at start.
#pragma once

#include <cstddef>

namespace range_nlm
{
namespace io
{

/// What preferHugePagesForBuffers did.
struct HeapSetup
{
  /// Allocations below this many bytes come from the heap (glibc's mmap threshold).
  std::size_t heap_below_bytes = 0;
  /// Bytes of heap marked for transparent huge pages (MADV_HUGEPAGE); 0 if none was.
  std::size_t marked_bytes = 0;
};

/// A filter run first touches tens of megabytes of buffers (about 65 MB for a VGA frame), and a
/// page fault per 4 KiB page costs a one-frame run most of its time where the kernel gives
/// transparent huge pages only to memory that asks for them (`madvise` mode, as on Ubuntu and on
/// many virtual machines); per-frame buffers that the allocator gives back to the kernel and
/// takes again are faulted in again every frame. This keeps buffers of up to 32 MB on the heap,
/// keeps freed heap (up to 1 GB) instead of giving it back, and grows the heap once by 180 MB of
/// address space marked for huge pages, which costs no memory until it is touched. Call it once,
/// at the start of a process, before the frames are allocated. With glibc only; elsewhere, or if
/// the allocator refuses the settings, it does nothing (and says so in the result). Where huge
/// pages are off the mark changes nothing; where they are always on it is already the case.
HeapSetup
preferHugePagesForBuffers();

} // namespace io
} // namespace range_nlm
