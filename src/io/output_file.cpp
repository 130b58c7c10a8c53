#include "output_file.h"

#include <range_nlm/io/pcd_file.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace range_nlm
{
namespace io
{
namespace detail
{

namespace
{
std::string
kindOf(mode_t mode)
{
  if (S_ISDIR(mode))
    return "a directory";
  if (S_ISBLK(mode))
    return "a block device";
  if (S_ISSOCK(mode))
    return "a socket";
  return "not a regular file, character device or FIFO";
}

/// `path` with every symbolic link of its last component followed (a dangling link gives the
/// path it points to). Sets `error` (errno) if a link cannot be read or links loop.
std::string
followLinks(const std::string& path, int& error)
{
  std::string current = path;
  for (int hop = 0; hop < 40; ++hop) {
    struct stat st;
    if (::lstat(current.c_str(), &st) != 0) {
      if (errno != ENOENT)
        error = errno;
      return current; // a new file (or an error reported by the caller)
    }
    if (!S_ISLNK(st.st_mode))
      return current;
    std::error_code ec;
    const fs::path link = fs::read_symlink(current, ec);
    if (ec) {
      error = ec.value();
      return current;
    }
    current = link.is_absolute() ? link.string() : (fs::path(current).parent_path() / link).string();
  }
  error = ELOOP;
  return current;
}
} // namespace

OutputFile::OutputFile(const std::string& path) : OutputFile(path, true) {}

OutputFile::OutputFile(const std::string& path, bool open) : path_(path)
{
  if (path.empty())
    throw InputError("the output path is empty; give a file name");
  if (path.back() == '/')
    throw InputError("'" + path + "': ends with '/', so it names a directory; refusing to write there (give a file "
                     "name)");
  int error = 0;
  target_ = followLinks(path, error);
  if (error != 0)
    fail("cannot resolve the output path", error);
  struct stat st;
  const bool exists = ::stat(target_.c_str(), &st) == 0;
  if (!exists && errno != ENOENT)
    fail("cannot examine the output path", errno);
  if (exists && (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode))) {
    const std::string kind = S_ISCHR(st.st_mode) ? "device" : "FIFO";
    if (!open) {
      if (::access(target_.c_str(), W_OK) != 0)
        fail("cannot open the " + kind + " for writing", errno);
      return;
    }
    do
      fd_ = ::open(target_.c_str(), O_WRONLY | O_CLOEXEC | O_NOCTTY);
    while (fd_ < 0 && errno == EINTR);
    if (fd_ < 0)
      fail("cannot open the " + kind + " for writing", errno);
    return;
  }
  if (exists && !S_ISREG(st.st_mode))
    throw InputError("'" + path_ + "'" + (target_ != path_ ? " (a link to '" + target_ + "')" : std::string()) +
                     ": is " + kindOf(st.st_mode) +
                     "; refusing to write over it (give a regular file, a character device such as /dev/null, or a "
                     "FIFO)");
  const fs::path target(target_);
  if (!open) {
    const fs::path directory = target.parent_path().empty() ? fs::path(".") : target.parent_path();
    if (::access(directory.c_str(), W_OK | X_OK) != 0)
      fail("cannot create the output file", errno);
    return;
  }
  temporary_ =
      (target.parent_path() / (temporaryPrefix(target.filename().string()) + std::to_string(::getpid()))).string();
  fd_ = ::open(temporary_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd_ < 0) {
    const int e = errno;
    temporary_.clear(); // nothing to remove
    fail("cannot create the output file", e);
  }
}

void
OutputFile::check(const std::string& path)
{
  const OutputFile probe(path, false);
}

OutputFile::~OutputFile()
{
  if (!committed_)
    discard();
}

void
OutputFile::discard() noexcept
{
  if (fd_ >= 0)
    ::close(fd_);
  fd_ = -1;
  if (!temporary_.empty())
    ::unlink(temporary_.c_str());
}

void
OutputFile::fail(const std::string& what, int error)
{
  discard();
  committed_ = true; // nothing left to clean up
  std::string message = "'" + path_ + "'";
  if (!target_.empty() && target_ != path_)
    message += " (a link to '" + target_ + "')";
  message += ": " + what + ": " + std::strerror(error);
  if (error == ENOSPC || error == EDQUOT)
    message += " (the disk is full; nothing was written under this name)";
  throw InputError(message);
}

int
OutputFile::tryWrite(const void* data, std::size_t size) noexcept
{
  if (error_ != 0)
    return error_;
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd_, p, size);
    if (n < 0) {
      if (errno == EINTR)
        continue;
      error_ = errno;
      return error_;
    }
    if (n == 0) { // no progress and no error: treat as a full device
      error_ = ENOSPC;
      return error_;
    }
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return 0;
}

void
OutputFile::write(const void* data, std::size_t size)
{
  if (tryWrite(data, size) != 0)
    fail("cannot write the output file", error_);
}

void
OutputFile::commit()
{
  if (error_ != 0)
    fail("cannot write the output file", error_);
  if (!direct() && ::fsync(fd_) != 0)
    fail("cannot write the output file to disk (fsync)", errno);
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0 && errno != EINTR)
    fail("cannot close the output file", errno);
  if (!direct() && ::rename(temporary_.c_str(), target_.c_str()) != 0)
    fail("cannot move the output file into place", errno);
  committed_ = true;
}

void
writeWholeFile(const std::string& path, const std::string& bytes)
{
  OutputFile out(path);
  out.write(bytes.data(), bytes.size());
  out.commit();
}

} // namespace detail

std::string
temporaryPrefix(const std::string& file_name)
{
  // The longest name a file system takes (NAME_MAX) less the longest process id (10 digits).
  constexpr std::size_t kLongest = 255 - 10;
  const std::string prefix = "." + file_name + ".tmp";
  if (prefix.size() <= kLongest)
    return prefix;
  // A long name is cut, and a hash of the whole name keeps names that share the cut part apart.
  std::uint64_t hash = 14695981039346656037ull; // FNV-1a
  for (unsigned char c : file_name)
    hash = (hash ^ c) * 1099511628211ull;
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(hash));
  const std::string tail = std::string("~") + hex + ".tmp";
  return "." + file_name.substr(0, kLongest - 1 - tail.size()) + tail;
}

} // namespace io
} // namespace range_nlm
