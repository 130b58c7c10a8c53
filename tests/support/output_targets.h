// Outputs every writer must handle alike (src/io/output_file.h): symbolic links (relative,
// dangling, chains), FIFOs, character devices, directories, sockets, full devices and disks. A
// fixture with a fresh directory, the special files made in it, and the checks of the writer
// matrix (tests/io/test_writer_matrix.cpp, tests/ros/test_bag_output.cpp), each run against one
// writer.
#pragma once

#include <gtest/gtest.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <poll.h>
#include <sys/mount.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/un.h>
#include <unistd.h>

namespace range_nlm
{
namespace test
{

/// What a writer did with an output: success, or its error message (exception or tool output).
struct WriteOutcome
{
  bool ok = false;
  std::string message;
};

/// One writer of the matrix: `write(path)` writes its (deterministic) output to `path`.
struct Writer
{
  std::string name;
  std::function<WriteOutcome(const std::string& path)> write;
};

/// Reads a FIFO in a thread from construction until finish(): opened read-write, so that the
/// writer's open never waits and the reader never sees an early end. finish(), called once the
/// writer is done, drains what is left and returns every byte received.
class FifoReader
{
public:
  explicit FifoReader(const std::string& fifo)
  {
    fd_ = ::open(fifo.c_str(), O_RDWR | O_CLOEXEC);
    if (fd_ < 0)
      return;
    thread_ = std::thread([this] {
      std::vector<char> buffer(1 << 16);
      for (;;) {
        pollfd p{fd_, POLLIN, 0};
        const int ready = ::poll(&p, 1, 200);
        if (ready > 0) {
          const ssize_t n = ::read(fd_, buffer.data(), buffer.size());
          if (n <= 0)
            break;
          received_.append(buffer.data(), std::size_t(n));
        } else if (done_) {
          break;
        }
      }
    });
  }
  ~FifoReader() { finish(); }
  FifoReader(const FifoReader&) = delete;
  FifoReader& operator=(const FifoReader&) = delete;

  bool opened() const { return fd_ >= 0; }
  const std::string& finish()
  {
    done_ = true;
    if (thread_.joinable())
      thread_.join();
    if (fd_ >= 0)
      ::close(fd_);
    fd_ = -1;
    return received_;
  }

private:
  int fd_ = -1;
  std::atomic<bool> done_{false};
  std::thread thread_;
  std::string received_;
};

class OutputTargets : public ::testing::Test
{
protected:
  void SetUp() override
  {
    char dir[] = "/tmp/range_nlm_outputs_XXXXXX";
    ASSERT_TRUE(::mkdtemp(dir));
    dir_ = dir;
  }
  void TearDown() override
  {
    if (mounted_)
      ::umount2(mount_point_.c_str(), MNT_DETACH);
    if (socket_ >= 0)
      ::close(socket_);
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return dir_ + "/" + name; }

  /// Names in `dir` that look like temporary files (".NAME.tmpPID").
  static std::vector<std::string> temporaries(const std::string& dir)
  {
    std::vector<std::string> found;
    for (const auto& entry : std::filesystem::directory_iterator(dir))
      if (entry.path().filename().string().find(".tmp") != std::string::npos)
        found.push_back(entry.path().filename().string());
    return found;
  }

  /// A character device node `name` in the test directory, (major, minor) = (1, 3) as /dev/null
  /// or (1, 7) as /dev/full; "" (with `why`) unless root. The system's own nodes are never used
  /// for a writer that could replace them.
  std::string deviceNode(const std::string& name, unsigned minor, std::string& why)
  {
    if (::geteuid() != 0) {
      why = "needs root to create a character device node with mknod";
      return "";
    }
    const std::string node = path(name);
    if (::mknod(node.c_str(), S_IFCHR | 0666, makedev(1, minor)) != 0) {
      why = "cannot create a device node here: " + std::string(std::strerror(errno));
      return "";
    }
    return node;
  }

  /// A device whose every write fails with ENOSPC: a node made like /dev/full as root, else the
  /// system's /dev/full (which a writer not running as root cannot replace); "" with `why`.
  std::string fullDevice(std::string& why)
  {
    if (::geteuid() == 0)
      return deviceNode("full", 7, why);
    if (!std::filesystem::exists("/dev/full")) {
      why = "this system has no /dev/full";
      return "";
    }
    return "/dev/full";
  }

  /// A Unix socket bound at `name` (closed by TearDown).
  std::string boundSocket(const std::string& name)
  {
    const std::string socket_path = path(name);
    socket_ = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    if (socket_ < 0 || socket_path.size() >= sizeof address.sun_path)
      return "";
    std::strcpy(address.sun_path, socket_path.c_str());
    if (::bind(socket_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0)
      return "";
    return socket_path;
  }

  /// Mounts a tmpfs of `size` (e.g. "1m") on dir/full_disk; false (with `why`) if impossible here.
  bool mountSmallDisk(const std::string& size, std::string& why)
  {
    if (::geteuid() != 0) {
      why = "needs root to mount a " + size + " tmpfs";
      return false;
    }
    mount_point_ = path("full_disk");
    std::filesystem::create_directories(mount_point_);
    if (::mount("tmpfs", mount_point_.c_str(), "tmpfs", 0, ("size=" + size).c_str()) != 0) {
      why = "cannot mount a tmpfs here: " + std::string(std::strerror(errno));
      return false;
    }
    mounted_ = true;
    return true;
  }

  /// The bytes `writer` writes to a regular file.
  std::string reference(const Writer& writer)
  {
    const std::string regular = path("regular.out");
    const WriteOutcome w = writer.write(regular);
    EXPECT_TRUE(w.ok) << w.message;
    std::ifstream in(regular, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_FALSE(bytes.empty());
    std::filesystem::remove(regular);
    return bytes;
  }

  static std::string read(const std::string& file)
  {
    std::ifstream in(file, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }

  // The checks of the matrix, one writer at a time.

  /// Symbolic links are followed: a relative dangling link gets its target created, a chain of
  /// absolute links its final target replaced; the links stay links, the bytes are the writer's.
  void expectLinksFollowed(const Writer& writer)
  {
    namespace fs = std::filesystem;
    const std::string expected = reference(writer);
    fs::create_directories(path("real"));
    fs::create_symlink("real/target.out", path("relative.out")); // dangling
    WriteOutcome w = writer.write(path("relative.out"));
    EXPECT_TRUE(w.ok) << w.message;
    EXPECT_TRUE(fs::is_symlink(path("relative.out")));
    ASSERT_TRUE(fs::is_regular_file(path("real/target.out")));
    EXPECT_TRUE(read(path("real/target.out")) == expected) << writer.name << ": other bytes through the link";

    fs::resize_file(path("real/target.out"), 1);
    fs::create_symlink(path("real/target.out"), path("absolute.out"));
    fs::create_symlink(path("absolute.out"), path("chain.out"));
    w = writer.write(path("chain.out"));
    EXPECT_TRUE(w.ok) << w.message;
    EXPECT_TRUE(fs::is_symlink(path("chain.out")));
    EXPECT_TRUE(fs::is_symlink(path("absolute.out")));
    EXPECT_TRUE(fs::is_regular_file(path("real/target.out")));
    EXPECT_TRUE(read(path("real/target.out")) == expected) << writer.name << ": other bytes through the chain";
    EXPECT_TRUE(temporaries(dir_).empty()) << temporaries(dir_).front();
    EXPECT_TRUE(temporaries(path("real")).empty()) << temporaries(path("real")).front();
  }

  /// A FIFO gets the writer's bytes and stays a FIFO.
  void expectFifoWrittenInPlace(const Writer& writer)
  {
    const std::string expected = reference(writer);
    const std::string fifo = path("out.fifo");
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0) << std::strerror(errno);
    FifoReader reader(fifo);
    ASSERT_TRUE(reader.opened()) << std::strerror(errno);
    const WriteOutcome w = writer.write(fifo);
    const std::string received = reader.finish();
    EXPECT_TRUE(w.ok) << w.message;
    EXPECT_TRUE(std::filesystem::is_fifo(fifo)) << writer.name << " replaced the FIFO";
    EXPECT_EQ(received.size(), expected.size());
    EXPECT_TRUE(received == expected) << writer.name << ": the FIFO's reader got other bytes";
    EXPECT_TRUE(temporaries(dir_).empty()) << temporaries(dir_).front();
  }

  /// A character device made like /dev/null is written to and stays a device (root only).
  void expectDeviceWrittenInPlace(const Writer& writer)
  {
    std::string why;
    const std::string null = deviceNode("null", 3, why);
    if (null.empty())
      GTEST_SKIP() << why;
    const WriteOutcome w = writer.write(null);
    EXPECT_TRUE(w.ok) << w.message;
    EXPECT_TRUE(std::filesystem::is_character_file(null)) << writer.name << " replaced the device";
    EXPECT_TRUE(temporaries(dir_).empty()) << temporaries(dir_).front();
  }

  /// A directory, a path ending in '/' and a socket are refused, with a message naming them and
  /// what they are; they stay as they were and nothing is created.
  void expectRefused(const Writer& writer)
  {
    namespace fs = std::filesystem;
    fs::create_directories(path("a_directory"));
    WriteOutcome w = writer.write(path("a_directory"));
    EXPECT_FALSE(w.ok);
    EXPECT_NE(w.message.find("'" + path("a_directory") + "'"), std::string::npos) << w.message;
    EXPECT_NE(w.message.find("is a directory"), std::string::npos) << w.message;
    EXPECT_TRUE(fs::is_directory(path("a_directory")));
    EXPECT_TRUE(fs::is_empty(path("a_directory")));

    // (range_nlm_denoise reads OUTPUT/ as an output directory, which must exist.)
    w = writer.write(path("new_directory") + "/");
    EXPECT_FALSE(w.ok);
    EXPECT_NE(w.message.find("'" + path("new_directory")), std::string::npos) << w.message;
    EXPECT_FALSE(fs::exists(path("new_directory")));

    const std::string socket_path = boundSocket("a_socket");
    ASSERT_FALSE(socket_path.empty()) << std::strerror(errno);
    w = writer.write(socket_path);
    EXPECT_FALSE(w.ok);
    EXPECT_NE(w.message.find("'" + socket_path + "'"), std::string::npos) << w.message;
    EXPECT_NE(w.message.find("is a socket"), std::string::npos) << w.message;
    EXPECT_TRUE(fs::is_socket(socket_path));
    EXPECT_TRUE(temporaries(dir_).empty()) << temporaries(dir_).front();
    for (const auto& entry : fs::directory_iterator(dir_))
      EXPECT_TRUE(entry.path().filename() == "a_directory" || entry.path().filename() == "a_socket" ||
                  entry.path().filename().string().rfind("in.", 0) == 0)
          << "left behind: " << entry.path();
  }

  /// A device that is full: the writer fails, naming it and "No space left on device"; the
  /// device stays a device and no file is left.
  void expectFullDeviceNamed(const Writer& writer)
  {
    std::string why;
    const std::string full = fullDevice(why);
    if (full.empty())
      GTEST_SKIP() << why;
    const WriteOutcome w = writer.write(full);
    EXPECT_FALSE(w.ok);
    EXPECT_NE(w.message.find("'" + full + "'"), std::string::npos) << w.message;
    EXPECT_NE(w.message.find("No space left on device"), std::string::npos) << w.message;
    EXPECT_TRUE(std::filesystem::is_character_file(full)) << writer.name << " replaced the device";
    EXPECT_TRUE(temporaries(dir_).empty()) << temporaries(dir_).front();
  }

  std::string dir_;
  std::string mount_point_;
  bool mounted_ = false;
  int socket_ = -1;
};

} // namespace test
} // namespace range_nlm
