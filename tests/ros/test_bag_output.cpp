// range_nlm_denoise --output-bag against every kind of output (tests/support/output_targets.h),
// as every other writer (tests/io/test_writer_matrix.cpp): a symbolic link is followed and stays
// a link, a FIFO or a character device gets the bag's bytes and stays what it is, a directory, a
// socket, a path ending in '/' or the input bag are refused before any message is filtered, and
// a full device or disk ends in exit status 1 with a message naming the bag, no file left.
#include "output_targets.h"
#include "ros_test_support.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <std_msgs/String.h>

#include <filesystem>
#include <fstream>
#include <string>

using namespace range_nlm;
using namespace range_nlm::test;
namespace fs = std::filesystem;

namespace
{

const char* const kTopic = "/camera/depth/points";

class BagOutput : public OutputTargets
{
protected:
  /// A bag of `frames` w x h clouds on kTopic and a string per frame on /log; with `unorganized`,
  /// the second cloud is a single row (filtering stops there without --keep-going).
  void writeBag(const std::string& bag_path, int frames, int w, int h, bool unorganized = false)
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
    for (int k = 0; k < frames; ++k) {
      const ros::Time t(1000 + k, 5000);
      std_msgs::String text;
      text.data = "frame " + std::to_string(k);
      bag.write("/log", t, text);
      sensor_msgs::PointCloud2 m = toPointCloud2(makeCloud(w, h, step(w / 2, 1.5, 2.0), 0.004, 300 + k), 1000 + k, 0);
      if (unorganized && k == 1) {
        m.width *= m.height;
        m.height = 1;
        m.row_step = m.width * m.point_step;
      }
      bag.write(kTopic, t, m);
    }
  }

  Writer bagWriter(const std::string& input) const
  {
    return {"Bag", [input](const std::string& out) {
              const CommandResult r =
                  runDenoise("--input-bag " + input + " --topic " + kTopic + " --output-bag " + out + " -q");
              EXPECT_NE(r.status, 134) << "aborted: " << r.output;
              return WriteOutcome{r.status == 0, r.output};
            }};
  }
};

TEST_F(BagOutput, SymbolicLinksAreFollowedAndStayLinks)
{
  writeBag(path("in.bag"), 3, 32, 24);
  expectLinksFollowed(bagWriter(path("in.bag")));
}

TEST_F(BagOutput, FifoGetsTheBagsBytes)
{
  writeBag(path("in.bag"), 3, 32, 24);
  expectFifoWrittenInPlace(bagWriter(path("in.bag")));
}

TEST_F(BagOutput, CharacterDeviceGetsTheBagsBytesAndStaysADevice)
{
  writeBag(path("in.bag"), 3, 32, 24);
  expectDeviceWrittenInPlace(bagWriter(path("in.bag")));
}

TEST_F(BagOutput, DirectorySocketAndTrailingSlashAreRefused)
{
  writeBag(path("in.bag"), 3, 32, 24);
  expectRefused(bagWriter(path("in.bag")));
}

TEST_F(BagOutput, FullDeviceIsNamedAndLeftAsItWas)
{
  writeBag(path("in.bag"), 3, 32, 24);
  expectFullDeviceNamed(bagWriter(path("in.bag")));
}

// Refused before any message is filtered: the input's second message would stop the run with
// "unorganized" if filtering began.
TEST_F(BagOutput, RefusedBeforeAnyMessageIsFiltered)
{
  writeBag(path("in.bag"), 3, 32, 24, true);
  const std::string input_bytes = read(path("in.bag"));
  const Writer writer = bagWriter(path("in.bag"));
  fs::create_directories(path("out"));
  fs::create_symlink("in.bag", path("link_to_input.bag"));
  for (const std::string& out : {path("out"), path("out/"), path("missing/"), path("in.bag"), path("link_to_input.bag")}) {
    const WriteOutcome w = writer.write(out);
    EXPECT_FALSE(w.ok) << out;
    EXPECT_EQ(w.message.find("unorganized"), std::string::npos) << out << ": filtered before refusing: " << w.message;
    EXPECT_NE(w.message.find("'" + out), std::string::npos) << w.message;
  }
  EXPECT_TRUE(read(path("in.bag")) == input_bytes);
  EXPECT_TRUE(fs::is_symlink(path("link_to_input.bag")));
  EXPECT_TRUE(fs::is_empty(path("out")));
  EXPECT_FALSE(fs::exists(path("missing")));
  EXPECT_TRUE(temporaries(dir_).empty()) << temporaries(dir_).front();
}

// A real full disk, filling up while the messages are written and while rosbag writes its
// index and closes the bag: exit status 1 (never an abort), the disk-full message naming the
// bag, nothing left on the disk but what was there.
TEST_F(BagOutput, FullDiskEndsInAMessageAndLeavesNoFile)
{
  std::string why;
  if (!mountSmallDisk("8m", why))
    GTEST_SKIP() << why;
  writeBag(path("in.bag"), 6, 128, 96);
  const Writer writer = bagWriter(path("in.bag"));
  const WriteOutcome whole = writer.write(path("whole.bag"));
  ASSERT_TRUE(whole.ok) << whole.message;
  const std::uintmax_t size = fs::file_size(path("whole.bag"));
  ASSERT_GT(size, 1000000u);
  const std::string out = mount_point_ + "/out.bag";
  // Room for a third of the bag, for all but its last 4 kB, and for all but its last 64 bytes.
  for (const std::uintmax_t room : {size / 3, size - 4096, size - 64}) {
    SCOPED_TRACE("room for " + std::to_string(room) + " of " + std::to_string(size) + " bytes");
    fs::remove(mount_point_ + "/filler");
    {
      std::ofstream filler(mount_point_ + "/filler", std::ios::binary);
      const std::string block(4096, 'x');
      while (filler.write(block.data(), block.size()))
        ;
    }
    const std::uintmax_t filled = fs::file_size(mount_point_ + "/filler");
    fs::resize_file(mount_point_ + "/filler", filled > room ? filled - (room / 4096) * 4096 : 0);
    const WriteOutcome w = writer.write(out);
    EXPECT_FALSE(w.ok);
    EXPECT_NE(w.message.find("'" + out + "'"), std::string::npos) << w.message;
    EXPECT_NE(w.message.find("No space left on device"), std::string::npos) << w.message;
    EXPECT_NE(w.message.find("the disk is full"), std::string::npos) << w.message;
    EXPECT_FALSE(fs::exists(out));
    EXPECT_TRUE(temporaries(mount_point_).empty()) << temporaries(mount_point_).front();
  }
}

} // namespace
