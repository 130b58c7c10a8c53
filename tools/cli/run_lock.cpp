#include "cli/run_lock.h"

#include "cli/cli.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

namespace range_nlm
{
namespace tools
{
namespace
{

/// "first..last (first.pcd .. last.pcd)" of a range of frames.
std::string
describe(const FrameRange& frames, const std::vector<std::string>& inputs)
{
  std::string text = std::to_string(frames.begin) + ".." + std::to_string(frames.end - 1);
  if (frames.end <= inputs.size() && !frames.empty())
    text += " (" + fileName(inputs[frames.begin]) + " .. " + fileName(inputs[frames.end - 1]) + ")";
  return text;
}

} // namespace

void
removeTemporaries(const std::vector<std::string>& outputs)
{
  namespace fs = std::filesystem;
  std::vector<std::string> prefixes;
  for (const std::string& output : outputs)
    prefixes.push_back(io::temporaryPrefix(fileName(output)));
  std::error_code ec;
  const fs::path dir = fs::path(outputs.front()).parent_path();
  for (const auto& entry : fs::directory_iterator(dir.empty() ? fs::path(".") : dir, ec)) {
    const std::string name = entry.path().filename().string();
    for (const std::string& prefix : prefixes)
      if (name.size() > prefix.size() && name.compare(0, prefix.size(), prefix) == 0 &&
          name.find_first_not_of("0123456789", prefix.size()) == std::string::npos) {
        fs::remove(entry.path(), ec);
        break;
      }
  }
}

OutputDirectoryLock::OutputDirectoryLock(const std::string& directory, bool exclusive)
{
  const std::string dir = directory.empty() ? "." : directory;
  fd_ = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0)
    throw InputError("cannot open output directory '" + dir + "': " + std::strerror(errno));
  if (::flock(fd_, (exclusive ? LOCK_EX : LOCK_SH) | LOCK_NB) != 0) {
    const int error = errno;
    ::close(fd_);
    fd_ = -1;
    if (error == EWOULDBLOCK)
      throw LockConflict("output directory '" + dir +
                       "' is in use by another range_nlm_denoise run; wait for it to end or write elsewhere");
    throw InputError("cannot lock output directory '" + dir + "': " + std::strerror(error));
  }
}

OutputDirectoryLock::~OutputDirectoryLock()
{
  if (fd_ >= 0)
    ::close(fd_);
}

FrameRangeLock::FrameRangeLock(const std::string& directory, const FrameRange& frames,
                               const std::vector<std::string>& inputs)
{
  if (frames.empty())
    return; // writes nothing
  const std::string path = joinPath(directory, kFileName);
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd_ < 0)
    throw InputError("cannot open the lock file '" + path + "' of the shards: " + std::strerror(errno));
  struct flock range = {};
  range.l_type = F_WRLCK;
  range.l_whence = SEEK_SET;
  range.l_start = static_cast<off_t>(frames.begin);
  range.l_len = static_cast<off_t>(frames.size());
  int command = F_OFD_SETLK;
  int result = ::fcntl(fd_, command, &range);
  if (result != 0 && errno == EINVAL) { // no open file description locks: the process's own
    command = F_SETLK;
    result = ::fcntl(fd_, command, &range);
  }
  if (result == 0)
    return;
  const int error = errno;
  struct flock holder = range;
  const bool known = ::fcntl(fd_, command == F_OFD_SETLK ? F_OFD_GETLK : F_GETLK, &holder) == 0 &&
                     holder.l_type != F_UNLCK;
  ::close(fd_);
  fd_ = -1;
  if (error != EAGAIN && error != EACCES)
    throw InputError("cannot lock frames in '" + path + "': " + std::strerror(error));
  std::string message = "frames " + describe(frames, inputs) + " of output directory '" + directory +
                        "' are being written by another range_nlm_denoise run";
  if (known) {
    const std::size_t first = static_cast<std::size_t>(holder.l_start);
    const std::size_t end = holder.l_len == 0 ? inputs.size() : first + static_cast<std::size_t>(holder.l_len);
    message += " (holding frames " + describe({first, std::min(end, inputs.size())}, inputs) + ")";
  }
  throw LockConflict(message + "; wait for it to end, or give each run its own shard");
}

FrameRangeLock::~FrameRangeLock()
{
  if (fd_ >= 0)
    ::close(fd_);
}

} // namespace tools
} // namespace range_nlm
