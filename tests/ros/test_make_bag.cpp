// range_nlm_make_bag: PCD frames in, a bag of PointCloud2 out, each message stamped and recorded
// at the same time, 1 / rate apart, every field and byte of the PCD kept; bad arguments and
// unreadable frames refused naming them, with no bag left behind.
#include "test_support.h"

#include <range_nlm/io/pcd_file.h>

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/PointCloud2.h>

#include <cmath>
#include <filesystem>
#include <vector>

#include <stdlib.h>

using namespace range_nlm;
using namespace range_nlm::test;
namespace fs = std::filesystem;

namespace
{

const std::string kMakeBag = RANGE_NLM_MAKE_BAG;

class MakeBag : public ::testing::Test
{
protected:
  void SetUp() override
  {
    char dir[] = "/tmp/range_nlm_make_bag_XXXXXX";
    ASSERT_TRUE(::mkdtemp(dir));
    dir_ = dir;
    for (int k = 0; k < 3; ++k) {
      pcl::PointCloud<pcl::PointXYZ> cloud = makeCloud(16, 12, step(8, 1.5, 2.0), 0.004, 40 + k);
      punchHoles(cloud, 0.1, 50 + k);
      const std::string path = dir_ + "/frame_" + std::to_string(k) + ".pcd";
      io::saveCloudAtomic(path, cloud);
      frames_.push_back(path);
    }
  }
  void TearDown() override { fs::remove_all(dir_); }

  CommandResult make(const std::string& args) { return runCommand(kMakeBag + " " + args); }

  std::string dir_;
  std::vector<std::string> frames_;
};

TEST_F(MakeBag, WritesTheFramesInOrderStampedAndRecordedOneOverTheRateApart)
{
  const std::string bag_path = dir_ + "/out.bag";
  const CommandResult r =
      make(bag_path + " " + frames_[0] + " " + frames_[1] + " " + frames_[2] + " --rate 4 --start 10 --topic /a/points");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("wrote 3 frames on /a/points at 4 Hz"), std::string::npos) << r.output;

  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  std::size_t k = 0;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    ASSERT_LT(k, frames_.size());
    EXPECT_EQ(m.getTopic(), "/a/points");
    const auto cloud = m.instantiate<sensor_msgs::PointCloud2>();
    ASSERT_TRUE(cloud);
    EXPECT_NEAR(cloud->header.stamp.toSec(), 10.0 + 0.25 * static_cast<double>(k), 1e-9);
    EXPECT_EQ(m.getTime(), cloud->header.stamp); // what rosbag play --clock publishes as /clock
    EXPECT_EQ(cloud->header.seq, k);
    EXPECT_EQ(cloud->header.frame_id, "camera_depth_optical_frame");
    // The PCD's own layout and bytes.
    const io::LoadedCloud pcd = io::loadCloud(frames_[k]);
    EXPECT_EQ(cloud->width, pcd.blob.width);
    EXPECT_EQ(cloud->height, pcd.blob.height);
    ASSERT_EQ(cloud->fields.size(), pcd.blob.fields.size());
    for (std::size_t f = 0; f < cloud->fields.size(); ++f) {
      EXPECT_EQ(cloud->fields[f].name, pcd.blob.fields[f].name);
      EXPECT_EQ(cloud->fields[f].offset, pcd.blob.fields[f].offset);
      EXPECT_EQ(cloud->fields[f].datatype, pcd.blob.fields[f].datatype);
    }
    EXPECT_EQ(cloud->point_step, pcd.blob.point_step);
    EXPECT_EQ(cloud->row_step, pcd.blob.row_step);
    EXPECT_TRUE(cloud->data == pcd.blob.data);
    ++k;
  }
  EXPECT_EQ(k, 3u);
}

TEST_F(MakeBag, BadArgumentsAndFramesAreRefusedNamingThemAndLeaveNoBag)
{
  const std::string bag_path = dir_ + "/out.bag";
  struct Case
  {
    std::string args;
    int status;
    std::string words;
  };
  const std::vector<Case> cases = {
      {bag_path, 2, "give the output bag and at least one PCD frame"},
      {bag_path + " " + frames_[0] + " --rate 0", 2, "--rate must be a positive number"},
      {bag_path + " " + frames_[0] + " --start -1", 2, "--start must be a time after 0"},
      {bag_path + " " + frames_[0] + " --topic points", 2, "--topic must be a global topic name"},
      {bag_path + " " + frames_[0] + " " + dir_ + "/missing.pcd", 1, "missing.pcd"},
  };
  for (const Case& c : cases) {
    const CommandResult r = make(c.args);
    EXPECT_EQ(r.status, c.status) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.words), std::string::npos) << c.args << "\n" << r.output;
    EXPECT_FALSE(fs::exists(bag_path)) << c.args;
    EXPECT_FALSE(fs::exists(bag_path + ".partial")) << c.args;
  }
}

} // namespace
