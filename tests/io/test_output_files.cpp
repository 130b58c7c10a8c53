// Where outputs go: a full disk gives a message naming the file and leaves no file behind (no
// SIGBUS from a memory-mapped writer); a symbolic link is followed, a character device or a FIFO
// is written directly, a block device, socket or directory is refused. Through the library
// (saveCloudAtomic, saveDepthPng) and through range_nlm_denoise.
#include "test_support.h"

#include <range_nlm/io/depth_image.h>
#include <range_nlm/io/pcd_file.h>

#include <gtest/gtest.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
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
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace range_nlm;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{

const std::string kMilk = std::string(RANGE_NLM_SOURCE_DIR) + "/data/milk_cartoon_all_small_clorox.pcd";

Cloud
smallCloud()
{
  return test::makeCloud(32, 24, test::plane({0.1, 0.0, 1.0}, 1.0), 0.002, 3);
}

/// A small organized PCD frame (64 x 48) at `path`: the special-file tests need an output, not a
/// large one (they run under the sanitizers too).
void
writeSmallInput(const std::string& path)
{
  io::saveCloudAtomic(path, test::makeCloud(64, 48, test::plane({0.1, 0.0, 1.0}, 1.0), 0.002, 4));
}

/// Names in `dir` that look like our temporary files (".NAME.tmpPID").
std::vector<std::string>
temporaries(const fs::path& dir)
{
  std::vector<std::string> found;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().filename().string().find(".tmp") != std::string::npos)
      found.push_back(entry.path().filename().string());
  return found;
}

std::string
errorOf(const std::function<void()>& f)
{
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

class OutputFiles : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() / ("range_nlm_output_files_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override
  {
    if (mounted_)
      ::umount2(mount_point_.c_str(), MNT_DETACH);
    fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  /// Mounts a tmpfs of `size` (e.g. "2m") on dir/full; false (with `why`) if that is impossible here.
  bool mountSmallDisk(const std::string& size, std::string& why)
  {
    if (::geteuid() != 0) {
      why = "needs root to mount a " + size + " tmpfs";
      return false;
    }
    mount_point_ = path("full");
    fs::create_directories(mount_point_);
    if (::mount("tmpfs", mount_point_.c_str(), "tmpfs", 0, ("size=" + size).c_str()) != 0) {
      why = "cannot mount a tmpfs here: " + std::string(std::strerror(errno));
      return false;
    }
    mounted_ = true;
    return true;
  }

  fs::path dir_;
  std::string mount_point_;
  bool mounted_ = false;
};

// A real full disk: a 2 MB tmpfs cannot hold the 4.9 MB output of a VGA frame.
TEST_F(OutputFiles, FullDiskGivesAMessageAndLeavesNoFile)
{
  std::string why;
  if (!mountSmallDisk("2m", why))
    GTEST_SKIP() << why;
  const std::string out = mount_point_ + "/out.pcd";
  const test::CommandResult r = test::runDenoise(kMilk + " " + out + " -q");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("'" + out + "'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("No space left on device"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::is_empty(mount_point_)) << "left behind: " << fs::directory_iterator(mount_point_)->path();

  // A depth PNG on a disk with a few kB left (the rest taken by a filler file).
  {
    std::ofstream filler(mount_point_ + "/filler", std::ios::binary);
    const std::string block(4096, 'x');
    while (filler.write(block.data(), block.size()))
      ;
  }
  const std::uintmax_t filled = fs::file_size(mount_point_ + "/filler");
  ASSERT_GT(filled, 8192u);
  fs::resize_file(mount_point_ + "/filler", filled - 8192);
  const std::string png = mount_point_ + "/out.png";
  const std::string tum = std::string(RANGE_NLM_SOURCE_DIR) + "/data/depth-images/tum-fr2-desk-pair/";
  const test::CommandResult p =
      test::runDenoise(tum + "1_depth.png " + png + " -q --intrinsics " + tum + "intrinsics.txt");
  EXPECT_EQ(p.status, 1) << p.output;
  EXPECT_NE(p.output.find("'" + png + "'"), std::string::npos) << p.output;
  EXPECT_NE(p.output.find("No space left on device"), std::string::npos) << p.output;
  EXPECT_FALSE(fs::exists(png));
  EXPECT_TRUE(temporaries(mount_point_).empty());
}

// /dev/full fails every write with ENOSPC: the same message through the library, no root needed.
TEST_F(OutputFiles, DeviceThatIsFullGivesTheSystemsReason)
{
  if (!fs::exists("/dev/full"))
    GTEST_SKIP() << "this system has no /dev/full";
  const Cloud cloud = smallCloud();
  const std::string message = errorOf([&] { io::saveCloudAtomic("/dev/full", cloud); });
  EXPECT_NE(message.find("'/dev/full'"), std::string::npos) << message;
  EXPECT_NE(message.find("No space left on device"), std::string::npos) << message;
  EXPECT_TRUE(fs::is_character_file("/dev/full"));
  const std::string png = errorOf([&] { saveDepthPng("/dev/full", cloud, 1000.0); });
  EXPECT_NE(png.find("'/dev/full'"), std::string::npos) << png;
  EXPECT_NE(png.find("No space left on device"), std::string::npos) << png;
}

// A symbolic link is followed: its target gets the frame (written atomically beside the target),
// the link stays a link. Relative, absolute and dangling links, PCD and PNG.
TEST_F(OutputFiles, SymbolicLinkIsFollowedAndStaysALink)
{
  const Cloud cloud = smallCloud();
  fs::create_directories(path("real"));
  fs::create_symlink("real/target.pcd", path("relative.pcd")); // dangling: the target does not exist yet
  io::saveCloudAtomic(path("relative.pcd"), cloud);
  EXPECT_TRUE(fs::is_symlink(path("relative.pcd")));
  ASSERT_TRUE(fs::is_regular_file(path("real/target.pcd")));
  EXPECT_EQ(io::loadCloud(path("real/target.pcd")).blob.width, 32u);

  fs::create_symlink(path("real/target.pcd"), path("absolute.pcd")); // the target exists now
  fs::create_symlink(path("absolute.pcd"), path("chain.pcd"));
  const test::CommandResult r = test::runDenoise(path("real/target.pcd") + " " + path("chain.pcd") + " -q --overwrite");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::is_symlink(path("chain.pcd")));
  EXPECT_TRUE(fs::is_symlink(path("absolute.pcd")));
  EXPECT_TRUE(fs::is_regular_file(path("real/target.pcd")));
  EXPECT_NE(test::readBytes(path("real/target.pcd")), "");

  fs::create_symlink("real/depth.png", path("depth.png"));
  saveDepthPng(path("depth.png"), cloud, 1000.0);
  EXPECT_TRUE(fs::is_symlink(path("depth.png")));
  EXPECT_EQ(readDepthPng(path("real/depth.png")).width, 32);
  EXPECT_TRUE(temporaries(dir_).empty());
  EXPECT_TRUE(temporaries(path("real")).empty());
}

// A FIFO is written directly (a temporary file renamed over it would replace it): the reader
// gets exactly the bytes of the same output written to a regular file.
TEST_F(OutputFiles, FifoIsWrittenDirectly)
{
  writeSmallInput(path("in.pcd"));
  const test::CommandResult regular = test::runDenoise(path("in.pcd") + " " + path("regular.pcd") + " -q");
  ASSERT_EQ(regular.status, 0) << regular.output;
  const std::string expected = test::readBytes(path("regular.pcd"));
  EXPECT_GT(expected.size(), 64u * 48 * 12);

  const std::string fifo = path("out.fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0) << std::strerror(errno);
  // Opened read-write, so that the tool's open never waits and the reader never sees an early
  // end; it reads until it has the expected bytes or nothing comes for 120 s (a tool that
  // replaced the FIFO writes nothing into it).
  const int fd = ::open(fifo.c_str(), O_RDWR | O_CLOEXEC);
  ASSERT_GE(fd, 0) << std::strerror(errno);
  std::string received;
  std::thread reader([&] {
    std::vector<char> buffer(1 << 16);
    while (received.size() < expected.size()) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 120000) <= 0)
        break;
      const ssize_t n = ::read(fd, buffer.data(), buffer.size());
      if (n <= 0)
        break;
      received.append(buffer.data(), std::size_t(n));
    }
  });
  const test::CommandResult r = test::runDenoise(path("in.pcd") + " " + fifo + " -q");
  reader.join();
  ::close(fd);
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::is_fifo(fifo));
  EXPECT_EQ(received.size(), expected.size());
  EXPECT_TRUE(received == expected) << "the FIFO's reader got other bytes";
  EXPECT_TRUE(temporaries(dir_).empty());
}

// A character device made like /dev/null (1, 3) is written to, and stays a device.
TEST_F(OutputFiles, CharacterDeviceIsWrittenDirectly)
{
  if (::geteuid() != 0)
    GTEST_SKIP() << "needs root to create a character device node with mknod";
  const std::string null = path("null");
  if (::mknod(null.c_str(), S_IFCHR | 0666, makedev(1, 3)) != 0)
    GTEST_SKIP() << "cannot create a device node here: " << std::strerror(errno);
  writeSmallInput(path("in.pcd"));
  const test::CommandResult r = test::runDenoise(path("in.pcd") + " " + null + " -q");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::is_character_file(null));
  EXPECT_TRUE(temporaries(dir_).empty());
  // (Never the system's /dev/null itself: a tool with this defect, run as root, would replace it.)
}

// Block devices, sockets and directories are refused with a message saying what they are; the
// node stays as it was.
TEST_F(OutputFiles, OtherSpecialFilesAreRefused)
{
  const Cloud cloud = smallCloud();
  fs::create_directories(path("a_directory.pcd"));
  std::string message = errorOf([&] { io::saveCloudAtomic(path("a_directory.pcd"), cloud); });
  EXPECT_NE(message.find("'" + path("a_directory.pcd") + "'"), std::string::npos) << message;
  EXPECT_NE(message.find("is a directory"), std::string::npos) << message;
  EXPECT_TRUE(fs::is_directory(path("a_directory.pcd")));

  const std::string socket_path = path("a_socket");
  const int sock = ::socket(AF_UNIX, SOCK_STREAM, 0);
  ASSERT_GE(sock, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  ASSERT_LT(socket_path.size(), sizeof address.sun_path);
  std::strcpy(address.sun_path, socket_path.c_str());
  ASSERT_EQ(::bind(sock, reinterpret_cast<sockaddr*>(&address), sizeof address), 0) << std::strerror(errno);
  writeSmallInput(path("in.pcd"));
  const test::CommandResult r = test::runDenoise(path("in.pcd") + " " + socket_path + " -q");
  ::close(sock);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("is a socket"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::is_socket(socket_path));
  EXPECT_TRUE(temporaries(dir_).empty());

  if (::geteuid() != 0)
    GTEST_SKIP() << "needs root to create a block device node with mknod (directory and socket checked)";
  const std::string block = path("a_block_device");
  if (::mknod(block.c_str(), S_IFBLK | 0600, makedev(7, 0)) != 0)
    GTEST_SKIP() << "cannot create a device node here: " << std::strerror(errno);
  message = errorOf([&] { io::saveCloudAtomic(block, cloud); });
  EXPECT_NE(message.find("is a block device"), std::string::npos) << message;
  EXPECT_TRUE(fs::is_block_file(block));
}

} // namespace
