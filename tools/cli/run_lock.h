// What keeps runs of range_nlm_denoise that write into one output directory from tripping over
// each other's files: a lock on the directory, a lock on the frames a --shard run writes, and the
// removal of the temporary files an interrupted run left (--resume), safe only under one of them.
#pragma once

#include "cli/shard.h"

#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{

/// For --resume: removes the temporary files an interrupted run left beside `outputs`
/// (".NAME.tmpPID", see io::temporaryPrefix). The caller holds the output directory exclusively
/// (OutputDirectoryLock), or with --shard those outputs (FrameRangeLock), so no running
/// range_nlm_denoise can own one of them.
void
removeTemporaries(const std::vector<std::string>& outputs);

/// Holds the directory a run writes into, so that runs cannot trip over each other's files: a
/// directory run, and any run with --resume (which removes temporary files), holds it
/// exclusively; a single-frame run shares it with other single-frame runs. A run that cannot get
/// the lock is refused with a message. An flock on the directory itself, so no file is left
/// behind; the kernel releases it however the process ends.
class OutputDirectoryLock
{
public:
  /// Throws InputError if the directory cannot be opened, LockConflict if another run holds it.
  OutputDirectoryLock(const std::string& directory, bool exclusive);
  ~OutputDirectoryLock();
  OutputDirectoryLock(const OutputDirectoryLock&) = delete;
  OutputDirectoryLock& operator=(const OutputDirectoryLock&) = delete;

private:
  int fd_ = -1;
};

/// Holds the frames a --shard run writes, so that shards of one recording can write into one
/// output directory at once while two runs that would write the same frame cannot: an exclusive
/// lock on the byte range [first frame, last frame + 1) of OUTPUT_DIR/.range_nlm_denoise.lock,
/// frame indices in the input's name order. Any two overlapping shards conflict, whatever their
/// N. Open file description locks (F_OFD_SETLK; the kernel releases them however the process
/// ends) are POSIX record locks, which NFS passes to the server, so shards on different nodes of
/// a cluster exclude each other on a shared file system too. The file stays (empty) behind.
class FrameRangeLock
{
public:
  static constexpr const char* kFileName = ".range_nlm_denoise.lock";

  /// Locks `frames` of `inputs` (nothing for an empty range). Throws LockConflict naming the frames
  /// (and those of the run holding them, where the kernel tells) if another run holds any of them.
  FrameRangeLock(const std::string& directory, const FrameRange& frames, const std::vector<std::string>& inputs);
  ~FrameRangeLock();
  FrameRangeLock(const FrameRangeLock&) = delete;
  FrameRangeLock& operator=(const FrameRangeLock&) = delete;

private:
  int fd_ = -1;
};

} // namespace tools
} // namespace range_nlm
