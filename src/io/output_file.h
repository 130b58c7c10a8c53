// Writing an output file with write(2), every return checked, so that a full disk or a failing
// device ends in a message naming the file (never SIGBUS from a memory-mapped writer) and no
// half-written file is left under any name.
#pragma once

#include <cstddef>
#include <string>

namespace range_nlm
{
namespace io
{
namespace detail
{

/// One output file, opened by the constructor according to what `path` is:
///  - missing or a regular file: written to ".NAME.tmpPID" beside it (io::temporaryPrefix), which
///    commit() fsyncs and renames over NAME; a failure or a destructor without commit() removes
///    the temporary file;
///  - a symbolic link (a chain of them, relative or absolute, dangling or not): followed, and its
///    final target written as above; the link stays a link;
///  - a character device (e.g. /dev/null) or a FIFO: opened and written directly, no temporary
///    file, no rename (a FIFO blocks until a reader opens it, as a shell redirection would);
///  - anything else (directory, block device, socket), or a path ending in '/': refused.
/// Every error throws io::InputError whose message names `path` and says what went wrong
/// (with strerror, e.g. "No space left on device").
class OutputFile
{
public:
  explicit OutputFile(const std::string& path);
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  /// Writes all `size` bytes (retrying short writes and EINTR). Throws on failure.
  void write(const void* data, std::size_t size);
  /// Same without throwing, for C callbacks (libpng): 0 on success, else the errno. The first
  /// failure is remembered and reported by commit().
  int tryWrite(const void* data, std::size_t size) noexcept;
  /// Flushes to the device (regular files: fsync), closes and renames into place. Throws on
  /// failure (and removes the temporary file).
  void commit();
  /// Removes the temporary file (closing the output) and throws io::InputError naming the path:
  /// "'PATH': WHAT: strerror(error)", with the disk-full note for ENOSPC and EDQUOT.
  [[noreturn]] void fail(const std::string& what, int error);

  /// Checks `path` as the constructor does (links followed; a directory, block device, socket or
  /// a path ending in '/' refused; for a new or regular file, its directory must exist and be
  /// writable) without creating or opening anything: for a writer that refuses an output before
  /// long work and opens it at the end. Throws io::InputError naming the path.
  static void check(const std::string& path);

  /// The path as given (for messages).
  const std::string& path() const { return path_; }
  /// True if the output is written directly (character device or FIFO).
  bool direct() const { return temporary_.empty(); }
  /// The temporary file (empty when direct()), for a library that writes a file by name with its
  /// own I/O (rosbag): it writes and closes that file, commit() fsyncs and renames it into place,
  /// and it is removed like any temporary file if commit() is not reached.
  const std::string& temporaryPath() const { return temporary_; }

private:
  /// Resolves and checks `path`; opens the output only if `open`.
  OutputFile(const std::string& path, bool open);
  void discard() noexcept;

  std::string path_;      // as given
  std::string target_;    // symbolic links resolved
  std::string temporary_; // empty: written directly
  int fd_ = -1;
  int error_ = 0; // first failure of tryWrite
  bool committed_ = false;
};

/// Writes `bytes` to `path` through an OutputFile (the whole file, committed).
void
writeWholeFile(const std::string& path, const std::string& bytes);

} // namespace detail
} // namespace io
} // namespace range_nlm
